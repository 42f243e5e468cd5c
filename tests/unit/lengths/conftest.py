"""Synthetic hands with known bone lengths, built with numpy only."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from handdb.clip import Clip
from handdb.hand.anatomy import hand_length_proportions
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.sidecar import parse_sidecar

#: Hand length of the synthetic subject, mm.
HAND_LENGTH_MM = 185.0

#: Wrist to thumb base, mm (no published proportion; a plausible adult value).
THUMB_BASE_MM = 28.0

#: In-plane angle of each finger from the forearm axis, degrees (thumb side positive).
FAN_DEG = {"thumb": 50.0, "index": 12.0, "middle": 0.0, "ring": -11.0, "little": -22.0}

#: Image scale of the synthetic camera, pixels per mm, and the image position of the wrist.
PIXELS_PER_MM = 3.0
WRIST_PIXEL = np.array([320.0, 420.0])


def true_lengths(skeleton: Skeleton) -> np.ndarray:
    """Known bone lengths in mm, ``(J,)``, NaN for the root."""
    lengths = hand_length_proportions(skeleton) * HAND_LENGTH_MM
    lengths[skeleton.index("thumb_cmc")] = THUMB_BASE_MM
    return lengths


def posed(skeleton: Skeleton, lengths: np.ndarray, curl: np.ndarray) -> np.ndarray:
    """Joint positions ``(T, J, 3)`` mm; every bone past the knuckles bends by ``curl``.

    ``curl`` is ``(T,)`` radians: each phalanx turns that much further away from the
    camera (+z) than its parent, so ``curl = 0`` is the flat hand facing the camera.
    """
    depth = skeleton.depth()
    xyz = np.zeros((curl.size, skeleton.n_joints, 3))
    for j in range(1, skeleton.n_joints):
        fan = np.radians(FAN_DEG.get(skeleton.fingers[j], 0.0))
        bend = curl * max(depth[j] - 1, 0)
        direction = np.stack([
            -np.sin(fan) * np.cos(bend) * np.ones_like(curl),
            -np.cos(fan) * np.cos(bend),
            np.sin(bend),
        ], axis=-1)
        xyz[:, j] = xyz[:, skeleton.parents[j]] + lengths[j] * direction
    return xyz


@pytest.fixture(scope="session")
def hand() -> SimpleNamespace:
    """The synthetic subject: ``true_lengths(skeleton)``, ``posed(...)``, hand length."""
    return SimpleNamespace(true_lengths=true_lengths, posed=posed,
                           hand_length_mm=HAND_LENGTH_MM)


@pytest.fixture
def make_clip(tmp_path):
    """Build a mediapipe21 clip from a curl per frame and optional sidecar extras."""

    def build(curl, *, bone_lengths=None, with_truth=False, hidden=()):
        skeleton = load_skeleton("mediapipe21")
        xyz = posed(skeleton, true_lengths(skeleton), np.asarray(curl, dtype=float))
        uv = xyz[..., :2] * PIXELS_PER_MM + WRIST_PIXEL
        uv[:, [skeleton.index(j) for j in hidden]] = np.nan
        sidecar = tmp_path / "synthetic.clip.json"
        sidecar.write_text(json.dumps({
            "skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
            "units": "mm", "camera": {"model": "orthographic"},
            "bone_lengths": bone_lengths or {},
        }))
        return Clip(spec=parse_sidecar(sidecar), skeleton=skeleton, uv=uv,
                    confidence=np.full(uv.shape[:2], np.nan),
                    truth=xyz if with_truth else None, source_format="synthetic",
                    source_files=(str(sidecar),), content_hash="0" * 64)

    return build
