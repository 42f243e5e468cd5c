"""Export a clip stored in the database as USD or BVH.

Reads the clip's ``clips`` row, its ``joints_3d`` and its ``bone_lengths`` from the
database (:class:`handdb.store.database.Store`) and hands them to :mod:`handdb.export.usd` or
:mod:`handdb.export.bvh`, chosen by the output file's suffix.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from handdb.errors import ParameterError, StoreError
from handdb.export.bvh import export_clip_bvh
from handdb.export.usd import LAYER_SUFFIXES, USDZ_SUFFIX, export_clip_usd
from handdb.hand.skeletons import Skeleton, bone_length_array, load_skeleton
from handdb.store.database import Store

BVH_SUFFIX = ".bvh"

#: Output suffixes :func:`export_stored_clip` can write.
EXPORT_SUFFIXES: tuple[str, ...] = (*LAYER_SUFFIXES, USDZ_SUFFIX, BVH_SUFFIX)


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
    joints = _read(store, "joints_3d", clip_id).select(
        ["frame", "joint_index", "x", "y", "z"]).to_pydict()
    bones = _read(store, "bone_lengths", clip_id).select(["bone", "length"]).to_pydict()
    skeleton = load_skeleton(clip["skeleton"])
    xyz = np.full((clip["n_frames"], skeleton.n_joints, 3), np.nan)
    positions = np.column_stack([joints[axis] for axis in "xyz"]).astype(np.float64)
    xyz[joints["frame"], joints["joint_index"]] = positions
    lengths = bone_length_array(skeleton, dict(zip(bones["bone"], bones["length"], strict=True)),
                                complete=True)
    return StoredMotion(clip_id=clip_id, skeleton=skeleton, hand=clip["hand"],
                        units=clip["units"], fps=clip["fps"], xyz=xyz, bone_lengths=lengths)


def export_stored_clip(
    db: str, clip_id: str, out: str | Path, *, keep_lengths: bool = False
) -> Path:
    """Export the stored clip ``clip_id`` to ``out`` (USD or BVH, by suffix).

    Parameters
    ----------
    db
        Database folder or fsspec URL.
    clip_id
        The clip to export.
    out
        Output file, one of :data:`EXPORT_SUFFIXES`; its folder is created if missing.
    keep_lengths
        USD only: give every bone its stored length instead of reproducing ``joints_3d``
        exactly (BVH bones always keep their lengths).

    Returns
    -------
    pathlib.Path
        ``out``.
    """
    out = Path(out)
    if out.suffix not in EXPORT_SUFFIXES:
        raise ParameterError(f"{out}: the suffix must be one of {EXPORT_SUFFIXES}")
    motion = read_stored_motion(db, clip_id)
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.suffix == BVH_SUFFIX:
        return export_clip_bvh(out, skeleton=motion.skeleton, xyz=motion.xyz,
                               bone_lengths=motion.bone_lengths, fps=motion.fps)
    return export_clip_usd(out, clip_id=clip_id, skeleton=motion.skeleton, xyz=motion.xyz,
                           bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units=motion.units, hand=motion.hand, keep_lengths=keep_lengths)
