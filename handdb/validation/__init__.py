"""Validation: a clip's 3D joints measured against its ground truth.

:mod:`handdb.validation.depth` gives the depth error of every joint (the thesis's Table
4.1), sign accuracy and MPJPE per lifting method, with a chart and a markdown summary.
"""

#: Version of validation against ground truth. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 6
