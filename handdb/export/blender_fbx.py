"""Convert a handdb glTF binary to FBX inside Blender; run by :mod:`handdb.export.fbx`.

Runs under Blender's Python, never imported by handdb::

    blender --background --factory-startup --python blender_fbx.py -- IN.glb OUT.fbx FPS N ID
    python blender_fbx.py IN.glb OUT.fbx FPS N ID      # a Python with the bpy module

Imports the glTF at the clip's frame rate (Blender converts its seconds to frames at the
scene's rate), so the armature's action spans frames ``0 .. N - 1``, then exports the
armature and its skinned mesh (not the bone display shapes the importer adds) as binary
FBX: Y up, -Z forward, the animation baked into a take named after the clip ``ID``, no leaf
bones added, lengths in FBX's centimetres (the scene is in metres).
"""

import sys

import bpy


def convert(source: str, target: str, fps: float, n_frames: int, clip_id: str) -> None:
    """Import ``source`` (glTF) and export it as FBX to ``target``."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.name = clip_id
    scene.render.fps, scene.render.fps_base = round(fps), round(fps) / fps
    bpy.ops.import_scene.gltf(filepath=source)
    scene.frame_start, scene.frame_end = 0, n_frames - 1
    bpy.ops.object.select_all(action="DESELECT")
    for armature in (o for o in scene.objects if o.type == "ARMATURE"):
        armature.select_set(True)
        for child in armature.children:
            child.select_set(True)
    bpy.ops.export_scene.fbx(filepath=target, object_types={"ARMATURE", "MESH"},
                             use_selection=True, add_leaf_bones=False, bake_anim=True,
                             bake_anim_use_all_actions=False, bake_anim_use_nla_strips=False,
                             axis_forward="-Z", axis_up="Y", apply_unit_scale=True)


if __name__ == "__main__":
    arguments = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    convert(arguments[0], arguments[1], float(arguments[2]), int(arguments[3]), arguments[4])
