"""3D marker tracks as dense arrays and as the ``markers_3d`` table."""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from handdb.clip import finite_points
from handdb.hand.skeletons import Skeleton
from handdb.ingest.observations import Positions
from handdb.store import tables


def dense_markers(positions: Positions) -> np.ndarray:
    """Markers of a reader's long-form rows as ``(T, J, 3) float64``, NaN where missing."""
    markers = np.full((positions.n_frames, positions.skeleton.n_joints, 3), np.nan)
    markers[positions.frame, positions.joint] = positions.xyz
    return markers


def markers_3d_table(clip_id: str, markers: np.ndarray, skeleton: Skeleton) -> pa.Table:
    """Table ``markers_3d``: one row per marker seen, clip units.

    Parameters
    ----------
    clip_id
        The clip.
    markers
        ``(T, J, 3) float64``, NaN where a marker is missing.
    skeleton
        The skeleton ordering the joint axis.
    """
    frame, joint = np.nonzero(finite_points(markers))
    xyz = markers[frame, joint]
    return tables.from_columns("markers_3d", {
        "clip_id": clip_id,
        "frame": frame.astype(np.int32),
        "joint": np.asarray(skeleton.joints)[joint],
        "joint_index": joint.astype(np.int32),
        "x": xyz[:, 0],
        "y": xyz[:, 1],
        "z": xyz[:, 2],
    })
