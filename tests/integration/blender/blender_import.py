"""Import a USD file into Blender (bpy) and describe what Blender made of it, as JSON.

Run with Blender's Python: ``python blender_import.py CLIP.usd FRAME [FRAME ...]``. Prints
one JSON object: the armature's bone names, the frame range of its action, and the world
position of every bone's head at each FRAME (Blender units, Blender's Z-up world).
"""

import json
import sys

import bpy


def main(path: str, frames: list[int]) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.usd_import(filepath=path)
    armatures = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    armature = armatures[0]
    action = armature.animation_data.action if armature.animation_data else None
    heads = {}
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        heads[frame] = {bone.name: list(armature.matrix_world @ bone.head)
                        for bone in armature.pose.bones}
    return {
        "armatures": len(armatures),
        "bones": [bone.name for bone in armature.data.bones],
        "action_frame_range": list(action.frame_range) if action else None,
        "scene_frame_range": [bpy.context.scene.frame_start, bpy.context.scene.frame_end],
        "fps": bpy.context.scene.render.fps / bpy.context.scene.render.fps_base,
        "meshes": [{"name": m.name, "vertex_groups": len(m.vertex_groups),
                    "armature_modifier": any(mod.type == "ARMATURE" for mod in m.modifiers)}
                   for m in meshes],
        "heads": heads,
    }


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1], [int(f) for f in sys.argv[2:]])))
