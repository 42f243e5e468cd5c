"""Export a clip as FBX, converted from handdb's glTF by Blender.

There is no open FBX SDK; Blender's FBX exporter is the well-kept open writer. The clip is
written as glTF (:func:`handdb.export.gltf.export_clip_gltf`: the same armature, skinned
mesh and animation) into a temporary folder, and Blender, run as a separate process (one
for a whole batch of clips: its start-up is most of a clip's cost), imports it and exports
binary FBX (:mod:`handdb.export.blender_fbx`): Y up, one armature
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

import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handdb.errors import MissingToolError, ParameterError, StageError
from handdb.export.gltf import export_clip_gltf
from handdb.export.staging import staged_file
from handdb.hand.skeletons import Skeleton

FBX_SUFFIX = ".fbx"

#: Environment variable naming Blender: an executable, or a Python with ``bpy``.
BLENDER_VARIABLE = "HANDDB_BLENDER"

#: Seconds Blender may take to start, once per batch, and then per clip: it starts in 1-2 s
#: and converts a clip in under one on two cores, so a hung Blender is found in minutes, not
#: after hours of a large batch.
BLENDER_START_TIMEOUT_S = 300.0
BLENDER_CLIP_TIMEOUT_S = 60.0

#: The script Blender runs.
CONVERTER = Path(__file__).with_name("blender_fbx.py")

#: Name prefix of the temporary folder beside the output where files are staged.
STAGING_PREFIX = ".fbx-export-"

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


@dataclass(frozen=True)
class FbxConversion:
    """A clip's glTF file that Blender converts to FBX.

    Attributes
    ----------
    clip_id
        The clip, naming the FBX take.
    source
        The glTF binary (:func:`~handdb.export.gltf.export_clip_gltf`, rigid bones).
    target
        Where Blender writes the FBX file.
    fps
        The clip's frame rate, frames per second.
    n_frames
        The clip's frames ``T``.
    """

    clip_id: str
    source: Path
    target: Path
    fps: float
    n_frames: int


def stage_gltf(folder: Path, name: str, *, clip_id: str, skeleton: Skeleton, xyz: np.ndarray,
               bone_lengths: np.ndarray, fps: float, units: str, hand: str) -> FbxConversion:
    """Write a clip's glTF into ``folder`` for Blender to convert to ``folder/<name>.fbx``.

    The motion's parameters are those of :func:`handdb.export.gltf.export_clip_gltf`
    (``xyz`` ``(T, J, 3) float64``, ``units``); bones always keep their lengths.
    """
    source = export_clip_gltf(folder / f"{name}.glb", clip_id=clip_id, skeleton=skeleton,
                              xyz=xyz, bone_lengths=bone_lengths, fps=fps, units=units,
                              hand=hand, keep_lengths=True)
    return FbxConversion(clip_id=clip_id, source=source, target=folder / f"{name}{FBX_SUFFIX}",
                         fps=float(fps), n_frames=len(xyz))


def convert_to_fbx(conversions: Sequence[FbxConversion]) -> dict[str, str]:
    """Convert glTF files to FBX in one Blender process (its start-up is paid once).

    Parameters
    ----------
    conversions
        What to convert; each target's folder must exist.

    Returns
    -------
    dict
        Clip id -> why Blender wrote no FBX file for it, for every conversion that failed
        (empty when all were written); a failure of one clip leaves the others' files.

    Raises
    ------
    MissingToolError
        If Blender is not installed (the message says how to get it).
    StageError
        If Blender did not finish within :data:`BLENDER_START_TIMEOUT_S` seconds and
        :data:`BLENDER_CLIP_TIMEOUT_S` per clip.
    """
    if not conversions:
        return {}
    command = blender_command()
    timeout = BLENDER_START_TIMEOUT_S + BLENDER_CLIP_TIMEOUT_S * len(conversions)
    with tempfile.TemporaryDirectory(prefix="handdb-fbx-") as tmp:
        listed, reported = Path(tmp) / "batch.json", Path(tmp) / "failures.json"
        listed.write_text(json.dumps({"failures": str(reported), "conversions": [
            {"source": str(c.source), "target": str(c.target), "fps": c.fps,
             "n_frames": c.n_frames, "clip_id": c.clip_id} for c in conversions]}))
        try:
            run = subprocess.run([*command, *_script_arguments(command, [str(listed)])],
                                 capture_output=True, text=True, check=False,
                                 timeout=timeout)
        except subprocess.TimeoutExpired:
            raise StageError(
                "Blender did not finish the FBX conversion of "
                f"{', '.join(c.clip_id for c in conversions)} in "
                f"{timeout:g} s") from None
        # no report: Blender died mid-batch, and a file it was writing may be cut short
        finished = reported.is_file()
        reasons = json.loads(reported.read_text()) if finished else {}
    tail = "\n".join((run.stdout + run.stderr).strip().splitlines()[-QUOTED_LINES:])
    return {c.clip_id: reasons.get(c.clip_id) or (
                f"Blender ({command[0]}, exit status {run.returncode}) wrote no complete FBX "
                f"file:\n{tail}")
            for c in conversions
            if not finished or c.clip_id in reasons or not c.target.is_file()}


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
    is replaced atomically. Many clips are converted in one Blender process by
    :func:`stage_gltf` and :func:`convert_to_fbx`.

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
        fails, quoting its error.
    """
    path = Path(path)
    if path.suffix != FBX_SUFFIX:
        raise ParameterError(f"{path}: the suffix must be {FBX_SUFFIX}")
    blender_command()
    with staged_file(path, STAGING_PREFIX) as staged:
        conversion = stage_gltf(staged.parent, staged.stem, clip_id=clip_id,
                                skeleton=skeleton, xyz=xyz, bone_lengths=bone_lengths,
                                fps=fps, units=units, hand=hand)
        failed = convert_to_fbx([conversion])
        if failed:
            raise StageError(f"{path}: Blender could not convert the clip to FBX: "
                             f"{failed[clip_id]}")
    return path
