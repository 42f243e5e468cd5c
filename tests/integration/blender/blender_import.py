"""Import a USD, glTF or FBX file into Blender (bpy); describe what Blender made of it, as JSON.

Run with Blender's Python: ``python blender_import.py CLIP FRAME [FRAME ...] [--fps FPS]``
(CLIP a ``.usd*``, ``.glb``, ``.fbx`` or ``.bvh`` file; FBX keys are imported from frame
0, not Blender's default 1; BVH with the importer's defaults: scale 1, and the first frame
at Blender's frame 1, the earliest its importer allows). Prints one JSON object: the
armature's bone names, the name and frame range of its action, and the world position of
every bone's head at each FRAME (Blender units, Blender's Z-up world). glTF keys its
animation in seconds and Blender's importer converts them to frames at the scene's rate:
``--fps`` sets that rate first.
"""

import argparse
import json

import bpy


def main(path: str, frames: list[int], fps: float | None = None) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if fps is not None:
        bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = round(fps), 1.0
    if path.endswith(".glb"):
        bpy.ops.import_scene.gltf(filepath=path)
    elif path.endswith(".fbx"):
        bpy.ops.import_scene.fbx(filepath=path, anim_offset=0.0)
    elif path.endswith(".bvh"):
        bpy.ops.import_anim.bvh(filepath=path)
    else:
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
        "action": action.name if action else None,
        "action_frame_range": list(action.frame_range) if action else None,
        "scene_frame_range": [bpy.context.scene.frame_start, bpy.context.scene.frame_end],
        "fps": bpy.context.scene.render.fps / bpy.context.scene.render.fps_base,
        "meshes": [{"name": m.name, "vertex_groups": len(m.vertex_groups),
                    "armature_modifier": any(mod.type == "ARMATURE" for mod in m.modifiers)}
                   for m in meshes],
        "heads": heads,
    }


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("path")
    parser.add_argument("frames", type=int, nargs="+")
    parser.add_argument("--fps", type=float)
    arguments = parser.parse_args()
    print(json.dumps(main(arguments.path, arguments.frames, arguments.fps)))
