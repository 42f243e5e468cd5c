"""Export: a clip's motion as files DCC, mocap and biomechanics tools open.

:mod:`handdb.export.rotations` turns joint positions into per-joint rotations (or takes a
marker fit's own); :mod:`handdb.export.usd` writes a UsdSkel animation with a skinned hand
mesh (:mod:`handdb.export.mesh`), :mod:`handdb.export.bvh` a BVH file,
:mod:`handdb.export.gltf` a skinned glTF binary, :mod:`handdb.export.fbx` FBX through
Blender, :mod:`handdb.export.trc` and :mod:`handdb.export.c3d` marker trajectories and
:mod:`handdb.export.preview` a PNG contact sheet; :mod:`handdb.export.stored` exports clips
already in the database. Every format is registered here, in
:data:`handdb.export.formats.FORMATS`; ``docs/export.md`` describes each.
"""

from handdb.export.formats import FORMATS, ExportFormat, register_format

#: Version of the USD, preview and chart files. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 3

for _entry in (
    ExportFormat("usd", (".usd", ".usdc", ".usda"), "handdb.export.stored:write_usd",
                 "UsdSkel animation with a skinned hand mesh (binary crate, or text .usda)",
                 "Blender 4+, Maya (maya-usd), Houdini, usdview, Omniverse", posed=True,
                 keys_placed_frames=True),
    ExportFormat("usdz", (".usdz",), "handdb.export.stored:write_usd",
                 "the USD animation packaged as one zip archive",
                 "Apple Quick Look and Reality Composer, Blender 4+, usdview", posed=True,
                 keys_placed_frames=True),
    ExportFormat("bvh", (".bvh",), "handdb.export.stored:write_bvh",
                 "Biovision Hierarchy: rigid bones, Euler rotation channels",
                 "Blender, MotionBuilder, Maya, Unity and Unreal importers", posed=True),
    ExportFormat("glb", (".glb",), "handdb.export.stored:write_glb",
                 "glTF 2.0 binary: skinned hand mesh, joint nodes, one animation (metres)",
                 "Blender, three.js / Babylon.js viewers, Unity (glTFast), Godot, Windows 3D "
                 "Viewer", posed=True),
    ExportFormat("fbx", (".fbx",), "handdb.export.stored:write_fbx",
                 "FBX binary, converted from the glTF by Blender (needs Blender installed)",
                 "Maya, MotionBuilder, 3ds Max, Unity, Unreal Engine, Blender", posed=True,
                 batch_writer="handdb.export.stored:write_fbx_batch"),
    ExportFormat("trc", (".trc",), "handdb.export.stored:write_trc",
                 "marker trajectories: every joint's 3D position per frame, tab-separated",
                 "OpenSim, Pose2Sim, Mokka, pandas", posed=False),
    ExportFormat("c3d", (".c3d",), "handdb.export.stored:write_c3d",
                 "marker trajectories in the biomechanics labs' binary format",
                 "Mokka, Vicon Nexus, Visual3D, OpenSim, ezc3d / c3d (Python)", posed=False),
):
    register_format(_entry)
del _entry

__all__ = ["FORMATS", "VERSION", "ExportFormat", "register_format"]
