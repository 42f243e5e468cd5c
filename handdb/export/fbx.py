"""Export a clip as FBX, converted from handdb's glTF by Blender.

There is no open FBX SDK; Blender's FBX exporter is the well-kept open writer. The clip is
written as glTF (:func:`handdb.export.gltf.export_clip_gltf`: the same armature, skinned
mesh and animation) into a temporary folder, and Blender, run as a separate process,
imports it and exports binary FBX (:mod:`handdb.export.blender_fbx`): Y up, one armature
with a bone per joint, the skinned hand mesh, the animation baked on frames ``0 .. T - 1``
at the clip's fps into a take named after the clip, lengths in centimetres as FBX expects.

Bones are rigid, as in BVH: every bone keeps its measured direction and takes its stored
length (``keep_lengths=True`` of the glTF export). Blender's FBX round trip drops a bone's
length changing from frame to frame (measured: up to 5 mm at the fingertips of a clip with
2 mm noise, against 0 for rigid bones), so the stretching that reproduces noisy positions
exactly in USD and glTF is not offered here.

Blender is found, in this order, at ``$HANDDB_BLENDER`` (a ``blender`` executable, or a
Python with Blender's ``bpy`` module, ``pip install bpy``), then as ``blender`` on the
``PATH``. Without it, :class:`~handdb.errors.MissingToolError` says how to get it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from handdb.errors import MissingToolError, ParameterError, StageError
from handdb.export.gltf import export_clip_gltf
from handdb.hand.skeletons import Skeleton

FBX_SUFFIX = ".fbx"

#: Environment variable naming Blender: an executable, or a Python with ``bpy``.
BLENDER_VARIABLE = "HANDDB_BLENDER"

#: Seconds a conversion may take; a few seconds per clip on two cores, most of it start-up.
BLENDER_TIMEOUT_S = 600.0

#: The script Blender runs.
CONVERTER = Path(__file__).with_name("blender_fbx.py")

#: Lines of Blender's output quoted when it fails.
QUOTED_LINES = 15

HOW_TO_GET_BLENDER = (
    "FBX export runs Blender, which was not found: install Blender 4.2 or newer "
    "(https://www.blender.org/download/, or your package manager) and put 'blender' on the "
    f"PATH, or set {BLENDER_VARIABLE} to the blender executable, or to the python of a "
    "Python 3.11 virtual environment where 'pip install bpy' ran. glTF (--format glb) "
    "holds the same animation and needs no Blender")


def blender_command() -> list[str]:
    """The command that runs a Python script in Blender: ``[*command, script, *args]``.

    Raises
    ------
    MissingToolError
        If ``$HANDDB_BLENDER`` names no file and there is no ``blender`` on the ``PATH``.
    """
    named = os.environ.get(BLENDER_VARIABLE)
    found = named if named and Path(named).is_file() else None
    if named and found is None:
        raise MissingToolError(f"{BLENDER_VARIABLE}={named} is not a file. "
                               + HOW_TO_GET_BLENDER)
    found = found or shutil.which("blender")
    if found is None:
        raise MissingToolError(HOW_TO_GET_BLENDER)
    if Path(found).name.startswith("python"):
        return [found]
    return [found, "--background", "--factory-startup", "--python-exit-code", "1", "--python"]


def _script_arguments(command: list[str], arguments: list[str]) -> list[str]:
    """``arguments`` as the converter receives them (Blender wants them after ``--``)."""
    return [str(CONVERTER), *arguments] if len(command) == 1 else [str(CONVERTER), "--",
                                                                    *arguments]


def export_clip_fbx(
    path: str | Path,
    *,
    clip_id: str,
    skeleton: Skeleton,
    xyz: np.ndarray,
    bone_lengths: np.ndarray,
    fps: float,
    units: str,
    hand: str,
) -> Path:
    """Write a clip as FBX through Blender (see the module doc).

    Parameters are those of :func:`handdb.export.gltf.export_clip_gltf` (bones always keep
    their lengths); ``path`` ends in ``.fbx``, its folder must exist, and an existing file
    is replaced atomically.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    MissingToolError
        If Blender is not installed (the message says how to get it).
    ParameterError, StageError
        As :func:`~handdb.export.gltf.export_clip_gltf`; ``StageError`` also when Blender
        fails, quoting its last lines.
    """
    path = Path(path)
    if path.suffix != FBX_SUFFIX:
        raise ParameterError(f"{path}: the suffix must be {FBX_SUFFIX}")
    command = blender_command()
    with tempfile.TemporaryDirectory(dir=path.parent, prefix=".fbx-export-") as tmp:
        source = export_clip_gltf(Path(tmp) / f"{path.stem}.glb", clip_id=clip_id,
                                  skeleton=skeleton, xyz=xyz, bone_lengths=bone_lengths,
                                  fps=fps, units=units, hand=hand, keep_lengths=True)
        written = Path(tmp) / path.name
        arguments = [str(source), str(written), repr(float(fps)), str(len(xyz)), clip_id]
        try:
            run = subprocess.run([*command, *_script_arguments(command, arguments)],
                                 capture_output=True, text=True, timeout=BLENDER_TIMEOUT_S,
                                 check=False)
        except subprocess.TimeoutExpired:
            raise StageError(f"{path}: Blender did not finish the FBX conversion in "
                             f"{BLENDER_TIMEOUT_S:g} s") from None
        if run.returncode != 0 or not written.is_file():
            tail = "\n".join((run.stdout + run.stderr).strip().splitlines()[-QUOTED_LINES:])
            raise StageError(f"{path}: Blender ({command[0]}) could not convert the clip to "
                             f"FBX (exit status {run.returncode}):\n{tail}")
        os.replace(written, path)
    return path
