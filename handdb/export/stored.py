"""Export clips stored in the database, one file per clip, in any export format.

Reads a clip's ``clips`` row, its ``joints_3d`` and its ``bone_lengths`` from the
database (:class:`handdb.store.database.Store`) and hands them to the writer of an export
format of :data:`handdb.export.formats.FORMATS`: chosen by the output file's suffix for one
clip (:func:`export_stored_clip`), by name for many (:func:`export_stored_clips`). The
writers here adapt a :class:`StoredMotion` to each format's module, imported only when a
file of that format is written.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from handdb.errors import ParameterError, StageError, StoreError
from handdb.export import placement
from handdb.export.clip_checks import unplaced_frames
from handdb.export.formats import FORMATS, ExportFormat, ExportOptions, format_for_suffix
from handdb.hand.skeletons import Skeleton, bone_length_array, load_skeleton
from handdb.store import tables
from handdb.store.database import Store


@dataclass(frozen=True)
class StoredMotion:
    """A clip's 3D motion as read back from the database.

    Attributes
    ----------
    clip_id, skeleton, hand, units, fps
        From the clip's ``clips`` row.
    xyz
        ``(T, J, 3) float64`` joint positions, clip units, camera frame; NaN where
        ``joints_3d`` has no position.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.
    """

    clip_id: str
    skeleton: Skeleton
    hand: str
    units: str
    fps: float
    xyz: np.ndarray
    bone_lengths: np.ndarray

    @property
    def unplaced_frames(self) -> int:
        """Frames with a joint that has no 3D position (a posed format cannot take them)."""
        return unplaced_frames(self.xyz)


def _read(store: Store, table: str, clip_id: str):
    data = store.read(table, clip_id)
    if data is None or data.num_rows == 0:
        raise StoreError(
            f"database {store.url} has no '{table}' rows for clip '{clip_id}'; build the "
            "database first (handdb build) or check the clip id (handdb sql "
            "'SELECT clip_id FROM clips')"
        )
    return data


def read_stored_motion(db: str, clip_id: str) -> StoredMotion:
    """Read a clip's joint positions and bone lengths from the database at ``db``.

    Raises
    ------
    StoreError
        If the clip has no ``clips``, ``joints_3d`` or ``bone_lengths`` rows.
    """
    store = Store(db)
    clip = _read(store, "clips", clip_id).to_pylist()[0]
    joints = _read(store, "joints_3d", clip_id)
    bones = _read(store, "bone_lengths", clip_id).select(["bone", "length"]).to_pydict()
    skeleton = load_skeleton(clip["skeleton"])
    xyz = tables.per_point(joints, ("x", "y", "z"), (clip["n_frames"], skeleton.n_joints)
                           ).astype(np.float64, copy=False)
    lengths = bone_length_array(skeleton, dict(zip(bones["bone"], bones["length"], strict=True)),
                                complete=True)
    return StoredMotion(clip_id=clip_id, skeleton=skeleton, hand=clip["hand"],
                        units=clip["units"], fps=clip["fps"], xyz=xyz, bone_lengths=lengths)


def write_usd(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion`` as UsdSkel (:mod:`handdb.export.usd`); reads ``keep_lengths``."""
    from handdb.export.usd import export_clip_usd

    return export_clip_usd(path, clip_id=motion.clip_id, skeleton=motion.skeleton,
                           xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units=motion.units, hand=motion.hand,
                           keep_lengths=options.keep_lengths)


def write_bvh(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion`` as BVH in metres (:mod:`handdb.export.bvh`); rigid bones."""
    from handdb.export.bvh import export_clip_bvh

    return export_clip_bvh(path, skeleton=motion.skeleton, xyz=motion.xyz,
                           bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units=motion.units)


def write_glb(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion`` as skinned glTF (:mod:`handdb.export.gltf`); reads ``keep_lengths``."""
    from handdb.export.gltf import export_clip_gltf

    return export_clip_gltf(path, clip_id=motion.clip_id, skeleton=motion.skeleton,
                            xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                            units=motion.units, hand=motion.hand,
                            keep_lengths=options.keep_lengths)


def write_fbx(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion`` as FBX through Blender (:mod:`handdb.export.fbx`); rigid bones."""
    from handdb.export.fbx import export_clip_fbx

    return export_clip_fbx(path, clip_id=motion.clip_id, skeleton=motion.skeleton,
                           xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units=motion.units, hand=motion.hand)


def write_fbx_batch(jobs: Iterable[tuple[StoredMotion, Path]], out_dir: Path,
                    options: ExportOptions) -> Iterator[ClipExport]:
    """Write each ``(motion, path)`` of ``jobs`` as FBX, converted by one Blender process.

    Each clip's glTF is staged in a temporary folder in ``out_dir`` as it comes (one clip's
    motion in memory at a time), then Blender converts them all and each FBX file is moved
    to its path; rigid bones.

    Yields
    ------
    ClipExport
        One per file written.

    Raises
    ------
    MissingToolError
        If Blender is not installed (before anything is written).
    StageError
        After the other clips' files are written, naming each clip Blender could not
        convert and why.
    """
    from handdb.export.fbx import STAGING_PREFIX, blender_command, convert_to_fbx, stage_gltf

    blender_command()
    with tempfile.TemporaryDirectory(dir=out_dir, prefix=STAGING_PREFIX) as tmp:
        staged = [(stage_gltf(Path(tmp), f"{index}", clip_id=motion.clip_id,
                              skeleton=motion.skeleton, xyz=motion.xyz,
                              bone_lengths=motion.bone_lengths, fps=motion.fps,
                              units=motion.units, hand=motion.hand), path)
                  for index, (motion, path) in enumerate(jobs)]
        failed = convert_to_fbx([conversion for conversion, _ in staged])
        for conversion, path in staged:
            if conversion.clip_id not in failed:
                os.replace(conversion.target, path)
                yield ClipExport(conversion.clip_id, path)
    if failed:
        raise StageError("Blender could not convert to FBX: " + "; ".join(
            f"clip {clip_id}: {reason}" for clip_id, reason in failed.items()))


def write_trc(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion``'s joint positions as TRC (:mod:`handdb.export.trc`)."""
    from handdb.export.trc import export_clip_trc

    return export_clip_trc(path, skeleton=motion.skeleton, xyz=motion.xyz, fps=motion.fps,
                           units=motion.units)


def write_c3d(motion: StoredMotion, path: Path, options: ExportOptions) -> Path:
    """Write ``motion``'s joint positions as C3D (:mod:`handdb.export.c3d`)."""
    from handdb.export.c3d import export_clip_c3d

    return export_clip_c3d(path, skeleton=motion.skeleton, xyz=motion.xyz, fps=motion.fps,
                           units=motion.units)


def placed_motion(entry: ExportFormat, motion: StoredMotion, options: ExportOptions
                  ) -> StoredMotion:
    """``motion`` where a file of format ``entry`` puts it (see ``options.at_origin``)."""
    if options.places_at_origin(entry):
        return replace(motion, xyz=placement.at_origin(motion.xyz, motion.skeleton))
    return motion


def _write(entry: ExportFormat, motion: StoredMotion, out: Path,
           options: ExportOptions) -> Path:
    out.parent.mkdir(parents=True, exist_ok=True)
    return entry.load()(placed_motion(entry, motion, options), out, options)


def export_stored_clip(
    db: str, clip_id: str, out: str | Path, *, keep_lengths: bool = False,
    at_origin: bool | None = None,
) -> Path:
    """Export the stored clip ``clip_id`` to ``out``, in the format its suffix names.

    Parameters
    ----------
    db
        Database folder or fsspec URL.
    clip_id
        The clip to export.
    out
        Output file, with a suffix of a format of :data:`~handdb.export.formats.FORMATS`;
        its folder is created if missing.
    keep_lengths
        Posed formats: give every bone its stored length instead of reproducing
        ``joints_3d`` exactly (BVH bones always keep their lengths).
    at_origin
        Move the hand to the origin, on the floor; ``None``: the format's default (see
        :class:`~handdb.export.formats.ExportOptions`).

    Returns
    -------
    pathlib.Path
        ``out``.

    Raises
    ------
    ParameterError
        If no format writes the suffix of ``out``.
    StoreError
        If the clip is not in the database.
    """
    out = Path(out)
    entry = format_for_suffix(out)
    return _write(entry, read_stored_motion(db, clip_id), out,
                  ExportOptions(keep_lengths=keep_lengths, at_origin=at_origin))


@dataclass(frozen=True)
class ClipExport:
    """What :func:`export_stored_clips` did with one clip.

    Attributes
    ----------
    clip_id
        The clip.
    path
        The file written, or ``None`` when the clip was skipped.
    skipped
        Why the clip was skipped, in words; ``None`` when it was written.
    """

    clip_id: str
    path: Path | None
    skipped: str | None = None


def export_stored_clips(
    db: str, format_name: str, out_dir: str | Path, clip_ids: list[str] | None = None,
    options: ExportOptions | None = None,
) -> Iterator[ClipExport]:
    """Export stored clips, one file per clip, ``<out_dir>/<clip_id><suffix>``.

    A clip a posed format cannot take (frames with joints gap filling could not place) is
    skipped with the reason, and so is a clip whose motion is not in the database; every
    other clip is written.

    Parameters
    ----------
    db
        Database folder or fsspec URL.
    format_name
        A format of :data:`~handdb.export.formats.FORMATS`.
    out_dir
        Output folder, created if missing.
    clip_ids
        The clips to export, in this order; ``None``: every clip of the database.
    options
        Passed to the format's writer; ``None``: the defaults of :class:`ExportOptions`.

    Yields
    ------
    ClipExport
        One per clip, as it is written or skipped; a format with a batch writer (FBX)
        writes every file at once, then reports the clips it skipped.

    Raises
    ------
    StageError
        When the batch writer could not write some clips: after the others' files are
        written and reported, naming each clip.
    UnknownNameError
        If ``format_name`` is not a format; the message lists those that are (raised before
        anything is read).
    ParameterError
        If ``out_dir`` is a file.
    StoreError
        If a clip of ``clip_ids`` is not in the database (before anything is written).
    """
    entry = FORMATS[format_name]
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise ParameterError(f"{out_dir} is a file, not a folder to receive one file per "
                             "clip")
    store = Store(db)
    stored = store.partition_keys("clips")
    if clip_ids is None:
        clip_ids = stored
    unknown = [clip_id for clip_id in clip_ids if clip_id not in stored]
    if unknown:
        raise StoreError(f"database {store.url} has no clip {', '.join(map(repr, unknown))}; "
                         "the clips are listed by handdb sql 'SELECT clip_id FROM clips'")
    options = options or ExportOptions()
    motions = _exportable(db, entry, clip_ids)
    write_batch = entry.load_batch()
    if write_batch is None:
        for item in motions:
            yield item if isinstance(item, ClipExport) else ClipExport(item.clip_id, _write(
                entry, item, out_dir / f"{item.clip_id}{entry.suffix}", options))
        return
    skipped: list[ClipExport] = []

    def jobs() -> Iterator[tuple[StoredMotion, Path]]:
        for item in motions:
            if isinstance(item, ClipExport):
                skipped.append(item)
            else:
                yield (placed_motion(entry, item, options),
                       out_dir / f"{item.clip_id}{entry.suffix}")

    out_dir.mkdir(parents=True, exist_ok=True)
    try:
        yield from write_batch(jobs(), out_dir, options)
    except StageError:
        yield from skipped
        raise
    yield from skipped


def _exportable(db: str, entry: ExportFormat, clip_ids: list[str]
                ) -> Iterator[StoredMotion | ClipExport]:
    """Each clip's stored motion, in turn, or why it is skipped.

    A clip a posed format cannot take (frames with joints gap filling could not place,
    unless the format keys only the placed frames) is skipped, and so is a clip whose
    motion is not in the database.
    """
    for clip_id in clip_ids:
        try:
            motion = read_stored_motion(db, clip_id)
        except StoreError as exc:
            yield ClipExport(clip_id, None, str(exc))
            continue
        if entry.posed and not entry.keys_placed_frames and motion.unplaced_frames:
            yield ClipExport(clip_id, None, (
                f"{motion.unplaced_frames} of {len(motion.xyz)} frames have joints gap "
                f"filling could not place, and {entry.name} needs every joint posed; "
                "USD keys the frames that place every joint, TRC and C3D write them as "
                "missing"))
            continue
        yield motion
