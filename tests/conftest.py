"""Shared test configuration: a quiet, isolated Prefect, and shared data fixtures."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from tests.support.motions import HingeMotion, make_hinge_motion, perturbed_hand
from tests.support.paths import DHG_SAMPLE, REAL_TOOLS, REPO

# Prefect reads these when it is first imported: set them before any test module does.
# Each xdist worker gets its own PREFECT_HOME (processes sharing a new database race on
# creating it); homes persist under .prefect/ so later runs reuse their databases.
_worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
_prefect_home = REPO / ".prefect" / f"test-{_worker}"
_prefect_home.mkdir(parents=True, exist_ok=True)
os.environ["PREFECT_HOME"] = str(_prefect_home)
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("PREFECT_SERVER_LOGGING_LEVEL", "CRITICAL")
# Run logs reach the API from INFO, as they do for users; the terminal shows warnings only.
os.environ.setdefault("PREFECT_LOGGING_LEVEL", "INFO")
os.environ.setdefault("PREFECT_LOGGING_HANDLERS_CONSOLE_LEVEL", "WARNING")
os.environ.setdefault("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS", "90")
os.environ.pop("PREFECT_API_URL", None)


@pytest.fixture(scope="session")
def dhg_sample() -> Path:
    """The real DHG capture in ../shared/data/dhg-sample; skips when it is absent."""
    if not DHG_SAMPLE.is_file():
        pytest.skip(f"shared data not present: {DHG_SAMPLE}")
    return DHG_SAMPLE


@pytest.fixture(scope="session")
def dhg_world(dhg_sample) -> np.ndarray:
    """The real DHG capture as ``(95, 22, 3)`` metres (skeleton ``dhg22``)."""
    return np.loadtxt(dhg_sample).reshape(-1, 22, 3)


@pytest.fixture(scope="session")
def dhg_mm(dhg_world) -> np.ndarray:
    """The real DHG capture in millimetres."""
    return dhg_world * 1000.0


@pytest.fixture(scope="session")
def dhg_bone_lengths(dhg_mm) -> np.ndarray:
    """The real DHG capture's bones at their median measured lengths, ``(J,)`` mm, 0 at the root."""
    from handdb.hand.skeletons import load_skeleton
    from tests.support.real_data import median_bone_lengths

    return np.nan_to_num(median_bone_lengths(dhg_mm, load_skeleton("dhg22")))


@pytest.fixture(scope="session")
def real_tools() -> Path:
    """The folder of real tool outputs in ../shared/data/real-tools; skips when absent."""
    if not REAL_TOOLS.is_dir():
        pytest.skip(f"shared data not present: {REAL_TOOLS}")
    return REAL_TOOLS


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


@pytest.fixture(params=["mediapipe21", "thesis21", "dhg22"])
def hinge_motion(request) -> HingeMotion:
    """Hinge motion of each skeleton preset, with known joint rotations."""
    from handdb.hand.skeletons import load_skeleton

    return make_hinge_motion(load_skeleton(request.param), n_frames=60)


@pytest.fixture
def mediapipe_motion() -> HingeMotion:
    """Hinge motion of ``mediapipe21``."""
    from handdb.hand.skeletons import load_skeleton

    return make_hinge_motion(load_skeleton("mediapipe21"), n_frames=40, seed=3)


@pytest.fixture(scope="session")
def model():
    """The kinematic model of the average right hand, mm."""
    from handdb.hand.model import build_hand_model

    return build_hand_model("right")


@pytest.fixture(scope="session")
def true_model(model):
    """A hand unlike ``model``: another size, bone lengths and palm."""
    return perturbed_hand(model, seed=7)


#: Demo clips put in the test database: one with complete tracks, one with gaps.
DEMO_DB_CLIPS = ("rapid-s01", "wave-s02")


@pytest.fixture(scope="session")
def demo_db(tmp_path_factory):
    """A database holding two demo clips, built in this process (no orchestrator)."""
    from handdb.build import BuildOptions
    from tests.support.building import build_demo_clips

    return build_demo_clips(tmp_path_factory.mktemp("gapfill-db"), DEMO_DB_CLIPS,
                            BuildOptions(export_usd=False))
