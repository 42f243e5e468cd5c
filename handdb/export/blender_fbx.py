"""Convert handdb glTF binaries to FBX inside Blender; run by :mod:`handdb.export.fbx`.

Runs under Blender's Python, never imported by handdb::

    blender --background --factory-startup --python blender_fbx.py -- BATCH.json
    python blender_fbx.py BATCH.json      # a Python with the bpy module

``BATCH.json`` is ``{"conversions": [...], "failures": FAILURES.json}``, each conversion
``{"source": IN.glb, "target": OUT.fbx, "fps": FPS, "n_frames": N, "clip_id": ID}``; one
Blender process converts them all, in turn, so its start-up is paid once per batch. A
conversion that fails does not stop the next; ``FAILURES.json`` is written at the end, an
object of clip id -> the error (empty when every file was written), and the exit status
is 1 when any failed.

Each glTF is imported, into an empty scene, at the clip's frame rate (Blender converts its
seconds to frames at the scene's rate), so the armature's action spans frames
``0 .. N - 1``, then the armature and its skinned mesh (not the bone display shapes the
importer adds) are exported as binary FBX: Y up, -Z forward, the animation baked into a
take named after the clip ``ID``, no leaf bones added, lengths in FBX's centimetres (the
scene is in metres).
"""

import json
import os
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


def convert_batch(batch: str) -> int:
    """Convert every conversion of the batch file ``batch``; return how many failed."""
    with open(batch) as handle:
        listed = json.load(handle)
    failures = {}
    for entry in listed["conversions"]:
        try:
            convert(entry["source"], entry["target"], float(entry["fps"]),
                    int(entry["n_frames"]), entry["clip_id"])
        except Exception as error:  # noqa: BLE001 - reported by clip; the others still run
            failures[entry["clip_id"]] = f"{type(error).__name__}: {' '.join(str(error).split())}"
            if os.path.exists(entry["target"]):  # what the exporter wrote before failing
                os.remove(entry["target"])
    with open(listed["failures"], "w") as handle:
        json.dump(failures, handle)
    return len(failures)


if __name__ == "__main__":
    arguments = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    sys.exit(1 if convert_batch(arguments[0]) else 0)
