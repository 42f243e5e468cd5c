"""The ``tracks_2d`` and ``truth_3d`` rows of a loaded clip."""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from handdb.clip import Clip, finite_points
from handdb.store.tables import from_columns, labels


def tracks_2d_table(clip: Clip) -> pa.Table:
    """Return the clip's 2D tracks as ingested, as a ``tracks_2d`` table.

    One row per (frame, joint) for which the source gave a position or a confidence;
    ``u, v`` null where the source marks the point missing, ``confidence`` null where it
    gives none. Points below ``min_confidence`` are kept: ``tracks_2d`` is the record of
    the input, not of what counts as observed.
    """
    frame, joint = np.nonzero(finite_points(clip.uv)
                              | np.isfinite(clip.confidence))
    return from_columns("tracks_2d", {
        "clip_id": clip.clip_id,
        "frame": frame,
        "joint": labels(clip.skeleton.joints, joint),
        "joint_index": joint,
        "u": clip.uv[frame, joint, 0],
        "v": clip.uv[frame, joint, 1],
        "confidence": clip.confidence[frame, joint],
    })


def truth_3d_table(clip: Clip) -> pa.Table | None:
    """Return the clip's ground truth as a ``truth_3d`` table, ``None`` without truth.

    One row per (frame, joint) with a ground-truth point, in the clip's units.
    """
    if clip.truth is None:
        return None
    frame, joint = np.nonzero(finite_points(clip.truth))
    return from_columns("truth_3d", {
        "clip_id": clip.clip_id,
        "frame": frame,
        "joint": labels(clip.skeleton.joints, joint),
        "joint_index": joint,
        **{axis: clip.truth[frame, joint, k] for k, axis in enumerate("xyz")},
    })
