"""Rows of the store's tables for tests that write a database by hand."""

import json

from handdb.store import tables


def truth_rows(clip_id, n_frames, offset=0.0):
    frames = list(range(n_frames))
    return tables.from_columns("truth_3d", {
        "clip_id": clip_id, "frame": frames, "joint": ["wrist"] * n_frames,
        "joint_index": [0] * n_frames, "x": [offset + f for f in frames],
        "y": [0.0] * n_frames, "z": [1.0] * n_frames,
    })


def clip_row(clip_id, key="k1"):
    return tables.from_columns("clips", {
        "clip_id": [clip_id], "content_hash": ["h"], "build_key": [key],
        "stage_keys": [json.dumps({"ingest": key})],
        "source_format": ["tracks_csv"], "source_files": [[f"{clip_id}.clip.json"]],
        "skeleton": ["mediapipe21"], "hand": ["right"], "fps": [30.0], "subject": ["s01"],
        "units": ["mm"], "camera_model": ["orthographic"], "fx": [None], "fy": [None],
        "cx": [None], "cy": [None], "image_width": [None], "image_height": [None],
        "n_frames": [3], "sampling": ["video"], "n_joints": [21], "n_observed": [63],
        "min_confidence": [0.5],
        "gap_fill_method": [None], "lift_method": [None], "depth_log_odds": [None],
        "depth_ambiguous": [None], "lift_note": [None], "has_truth": [True],
        "flagged": [False], "flag_reasons": [[]],
        "sidecar": ["{}"], "usd_path": [None], "handdb_version": ["0"],
    })
