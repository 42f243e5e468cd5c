"""Export: a clip's motion as files DCC tools open.

:mod:`handdb.export.rotations` turns joint positions into per-joint rotations (or takes a
marker fit's own); :mod:`handdb.export.usd` writes a UsdSkel animation with a skinned hand
mesh (:mod:`handdb.export.mesh`), :mod:`handdb.export.bvh` a BVH file and
:mod:`handdb.export.preview` a PNG contact sheet; :mod:`handdb.export.stored` exports a
clip already in the database.
"""

#: Version of the USD, preview and chart files. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 1
