"""Bone lengths: X-ray joint ratios and the length of every bone of every clip.

:mod:`handdb.lengths.ratios` turns X-ray phalanx measurements (Chaudhry et al.) into relative
segment ratios per cohort; :mod:`handdb.lengths.bone_lengths` gives each bone of a clip a
length and says where it came from.
"""

#: Version of every bone's length. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 4
