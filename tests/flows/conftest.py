import json
from pathlib import Path

import numpy as np
import pytest

from handdb.readers import get_format
from handdb.skeletons import load_skeleton
from handdb.synthetic import synthesize_clip

N_FRAMES = 40


def _write_clip(inbox: Path, clip_id: str, *, seed: int, fmt: str = "tracks_csv",
                truth: bool = True) -> Path:
    """Write a short synthetic clip; return its track file."""
    clip = synthesize_clip("wave", N_FRAMES, seed=seed)
    skeleton = load_skeleton(clip.skeleton)
    (inbox / f"{clip_id}.clip.json").write_text(json.dumps(clip.sidecar(subject=f"s{seed}")))
    track = inbox / f"{clip_id}{get_format(fmt).suffix}"
    get_format(fmt).write(track, clip.uv, np.full(clip.uv.shape[:2], 0.9), skeleton)
    if truth:
        get_format("truth_csv").write(inbox / f"{clip_id}.truth.csv", clip.xyz, skeleton)
    return track


@pytest.fixture(scope="session")
def write_clip():
    """``write_clip(inbox, clip_id, seed=, fmt=, truth=)`` writes a short synthetic clip."""
    return _write_clip


@pytest.fixture
def n_frames() -> int:
    """Frames of every clip :func:`write_clip` writes."""
    return N_FRAMES


@pytest.fixture
def inbox(tmp_path) -> Path:
    """An inbox of three good clips."""
    path = tmp_path / "inbox"
    path.mkdir()
    for seed, clip_id in enumerate(["alpha", "bravo", "charlie"]):
        _write_clip(path, clip_id, seed=seed)
    return path
