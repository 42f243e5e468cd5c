"""Shared test configuration: a quiet, isolated Prefect, and shared data fixtures."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"

# Prefect reads these when it is first imported: set them before any test module does.
# Each xdist worker gets its own PREFECT_HOME (processes sharing a new database race on
# creating it); homes persist under .prefect/ so later runs reuse their databases.
_worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
_prefect_home = REPO / ".prefect" / f"test-{_worker}"
_prefect_home.mkdir(parents=True, exist_ok=True)
os.environ["PREFECT_HOME"] = str(_prefect_home)
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("PREFECT_SERVER_LOGGING_LEVEL", "CRITICAL")
os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
os.environ.setdefault("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS", "90")
os.environ.pop("PREFECT_API_URL", None)


@pytest.fixture(scope="session")
def dhg_sample() -> Path:
    """The real DHG capture in ../shared/data/dhg-sample; skips when it is absent."""
    path = SHARED_DATA / "dhg-sample" / "skeletons_world.txt"
    if not path.is_file():
        pytest.skip(f"shared data not present: {path}")
    return path


N_FRAMES = 40


def _write_clip(inbox: Path, clip_id: str, *, seed: int, fmt: str = "tracks_csv",
                truth: bool = True) -> Path:
    """Write a short synthetic clip; return its track file."""
    from handdb.hand.skeletons import load_skeleton
    from handdb.ingest import get_format
    from handdb.synthetic import synthesize_clip

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
