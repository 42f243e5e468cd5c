"""A processed clip's rows: every per-clip table of ``schemas/tables``, ready to commit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb import __version__
from handdb.build.keys import build_key
from handdb.build.stages import ClipResult
from handdb.clip import finite_points
from handdb.ingest import inbox_relative, tracks_2d_table, truth_3d_table
from handdb.lengths.bone_lengths import bone_lengths_table
from handdb.lifting import LiftResult
from handdb.markers.fit import joint_angles_table
from handdb.markers.tables import markers_3d_table
from handdb.store import tables


def _flat(values: np.ndarray | None, n: int) -> np.ndarray:
    if values is None:
        return np.full(n, np.nan)
    return np.asarray(values, dtype=np.float64).reshape(n)


def joints_3d_table(result: ClipResult) -> pa.Table:
    """Rows of ``joints_3d``: one per frame and joint of the clip's skeleton."""
    clip, lifted = result.clip, result.lifted
    n_frames, n_joints = clip.observed.shape
    n = n_frames * n_joints
    joint_index = np.tile(np.arange(n_joints, dtype=np.int32), n_frames)
    uv = result.uv.reshape(n, 2)
    if result.fill is not None:
        filled = result.fill.filled.reshape(n)
        fill_codes = np.zeros(n, dtype=np.int32)
        fill_names, fill_codes[filled] = np.unique(result.fill.fill_method.reshape(n)[filled],
                                                   return_inverse=True)
        fill_method = tables.labels(fill_names, fill_codes, filled)
    else:
        filled, fill_method = np.zeros(n, dtype=bool), pa.nulls(n, pa.string())
    xyz = lifted.xyz.reshape(n, 3) if lifted is not None else np.full((n, 3), np.nan)
    lifted_rows = finite_points(xyz)
    residual = result.fit.residual.reshape(n) if result.fit is not None else np.full(n, np.nan)
    flagged = (result.verdict.rows.reshape(n) if result.verdict is not None
               else np.zeros(n, dtype=bool))
    return tables.from_columns("joints_3d", {
        "clip_id": clip.clip_id,
        "frame": np.repeat(np.arange(n_frames, dtype=np.int32), n_joints),
        "joint": tables.labels(clip.skeleton.joints, joint_index),
        "joint_index": joint_index,
        "u": uv[:, 0],
        "v": uv[:, 1],
        "observed": clip.observed.reshape(n),
        "confidence": clip.confidence.reshape(n),
        "filled": filled,
        "fill_method": fill_method,
        "x": xyz[:, 0],
        "y": xyz[:, 1],
        "z": xyz[:, 2],
        "lift_method": (tables.labels([lifted.method], np.zeros(n), lifted_rows)
                        if lifted is not None else pa.nulls(n, pa.string())),
        "scale": (np.repeat(lifted.scale, n_joints) if lifted is not None
                  else np.full(n, np.nan)),
        "sign_confidence": _flat(lifted.sign_confidence if lifted else None, n),
        "length_inconsistency": _flat(lifted.length_inconsistency if lifted else None, n),
        "residual": pa.array(residual, from_pandas=True),
        "flagged": flagged,
    })


def _depth_confidence(lifted: LiftResult | None) -> dict[str, list]:
    """The ``clips`` columns of the lifting's doubt about the clip's depth pose.

    ``depth_log_odds`` and ``depth_ambiguous`` are NULL where the method does not weigh
    the mirror (marker fits, ``thesis``, ``model-fit``).
    """
    if lifted is None:
        return dict.fromkeys(("depth_log_odds", "depth_ambiguous", "lift_note"), [None])
    odds = lifted.mirror_log_odds
    return {
        "depth_log_odds": [odds],
        "depth_ambiguous": [None if odds is None else lifted.mirror_ambiguous],
        "lift_note": [lifted.note or None],
    }


def clips_table(result: ClipResult, source_files: list[str]) -> pa.Table:
    """The clip's one row of ``clips``."""
    clip, spec = result.clip, result.clip.spec
    camera = spec.camera
    return tables.from_columns("clips", {
        "clip_id": [clip.clip_id],
        "content_hash": [clip.content_hash],
        "build_key": [build_key(result.keys)],
        "stage_keys": [json.dumps(result.keys)],
        "source_format": [clip.source_format],
        "source_files": [source_files],
        "skeleton": [spec.skeleton],
        "hand": [spec.hand],
        "fps": [spec.fps],
        "subject": [spec.subject],
        "units": [spec.units],
        "camera_model": [camera.model],
        "fx": [camera.fx], "fy": [camera.fy], "cx": [camera.cx], "cy": [camera.cy],
        "image_width": [spec.image_width],
        "image_height": [spec.image_height],
        "n_frames": [clip.n_frames],
        "sampling": [clip.sampling],
        "n_joints": [clip.skeleton.n_joints],
        "n_observed": [int(clip.observed.sum())],
        "min_confidence": [clip.min_confidence],
        "gap_fill_method": [result.fill.method if result.fill else None],
        "lift_method": [result.lifted.method if result.lifted else None],
        **_depth_confidence(result.lifted),
        "has_truth": [clip.truth is not None],
        "flagged": [result.verdict is not None and result.verdict.flagged],
        "flag_reasons": [list(result.verdict.reasons) if result.verdict is not None else []],
        "sidecar": [spec.raw],
        "usd_path": [result.usd_path],
        "handdb_version": [__version__],
    })


def clip_tables(result: ClipResult, inbox: str | Path) -> dict[str, pa.Table]:
    """Every per-clip table of the result, for :meth:`~handdb.store.Store.commit_clip`."""
    clip = result.clip
    out = {
        "clips": clips_table(result, [inbox_relative(f, inbox) for f in clip.source_files]),
        "tracks_2d": tracks_2d_table(clip),
        "joints_3d": joints_3d_table(result),
    }
    truth = truth_3d_table(clip)
    if truth is not None:
        out["truth_3d"] = truth
    if result.bones is not None:
        out["bone_lengths"] = bone_lengths_table(clip.clip_id, clip.spec.subject, clip.skeleton,
                                                 result.bones)
    if result.validation is not None:
        out["validation_joint"] = result.validation
    if clip.markers is not None:
        out["markers_3d"] = markers_3d_table(clip.clip_id, clip.markers, clip.skeleton)
    if result.fit is not None:
        out["joint_angles"] = joint_angles_table(clip.clip_id, result.fit.model,
                                                 result.fit.poses)
    return out
