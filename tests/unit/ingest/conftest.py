"""Fixtures for the reader tests: a synthetic 2D hand track and sidecar writing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from handdb.clip import ClipSpec
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.sidecar import parse_sidecar

SIDECAR = {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
           "units": "mm", "camera": {"model": "orthographic"}}


def hand_track(skeleton: Skeleton, n_frames: int = 12, seed: int = 0) -> np.ndarray:
    """A moving 2D hand, ``(T, J, 2)`` pixels: fingers as rays from the wrist."""
    rng = np.random.default_rng(seed)
    depth = skeleton.depth()
    finger_angle = {"thumb": -0.9, "index": -0.35, "middle": 0.0, "ring": 0.3,
                    "little": 0.6, "palm": 0.0}
    angle = np.array([finger_angle[f] for f in skeleton.fingers])
    t = np.arange(n_frames)[:, None]
    bend = 0.2 * np.sin(t / 3.0) * depth
    radius = 38.0 * depth
    wrist = np.array([320.0, 400.0]) + rng.normal(0, 2.0, (n_frames, 1, 2))
    rays = np.stack([np.sin(angle + bend), -np.cos(angle + bend)], axis=-1)
    return wrist + radius[None, :, None] * rays


@pytest.fixture
def mediapipe21() -> Skeleton:
    return load_skeleton("mediapipe21")


@pytest.fixture
def thesis21() -> Skeleton:
    return load_skeleton("thesis21")


@pytest.fixture
def write_sidecar():
    """Write ``<clip_id>.clip.json`` in a folder, with keys overriding the defaults."""

    def write(folder: Path, clip_id: str = "clip", **overrides) -> Path:
        path = folder / f"{clip_id}.clip.json"
        path.write_text(json.dumps(SIDECAR | overrides))
        return path

    return write


@pytest.fixture
def spec_for(write_sidecar):
    """Parse a freshly written sidecar: ``spec_for(tmp_path, **overrides)``."""

    def make(folder: Path, clip_id: str = "clip", **overrides) -> ClipSpec:
        return parse_sidecar(write_sidecar(folder, clip_id, **overrides))

    return make


@pytest.fixture
def noisy_track(mediapipe21):
    """A track with hidden points (NaN) and confidences, some below the default 0.5.

    Returns ``uv (T, J, 2)``, ``confidence (T, J)``.
    """
    uv = hand_track(mediapipe21)
    rng = np.random.default_rng(1)
    confidence = np.round(rng.uniform(0.55, 1.0, uv.shape[:2]), 3)
    confidence[rng.random(confidence.shape) < 0.15] = 0.2
    uv[rng.random(confidence.shape) < 0.1] = np.nan
    uv[3, :] = np.nan
    return uv, confidence
