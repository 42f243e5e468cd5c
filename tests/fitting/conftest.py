"""Shared fixtures of the model-fitting tests: a template hand, a different 'true' hand
and smooth motion drawn from the model itself."""

from __future__ import annotations

import numpy as np
import pytest

from handdb.hand.model import N_DOF, HandModel, build_hand_model


def perturbed_hand(model: HandModel, seed: int) -> HandModel:
    """A hand of another size (±10 %), bones varying ±5 % more, and another palm shape."""
    rng = np.random.default_rng(seed)
    size = rng.choice([0.9, 1.1])
    lengths = model.bone_lengths * size * rng.uniform(0.95, 1.05, model.bone_lengths.shape)
    directions = model.rest_directions.copy()
    directions[model.palm_joints] += rng.normal(0.0, 0.04, (len(model.palm_joints), 3))
    return model.with_geometry(lengths, directions)


def smooth_poses(model: HandModel, n_frames: int, seed: int) -> np.ndarray:
    """``(n_frames, 33)`` poses moving smoothly inside the joint limits (mm, rad)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames)[:, None]
    lower = np.maximum(model.lower, -np.pi / 3)
    upper = np.minimum(model.upper, np.pi / 3)
    middle, half = (upper + lower) / 2, (upper - lower) / 2
    phase = rng.uniform(0, 2 * np.pi, N_DOF)
    speed = rng.uniform(0.03, 0.12, N_DOF)
    poses = middle + 0.6 * half * np.sin(speed * t + phase)
    poses[:, :3] = [0.0, 0.0, 400.0] + 30.0 * np.sin(0.05 * t + phase[:3])
    poses[:, 3:6] = [0.3, -0.2, 0.4] + 0.3 * np.sin(0.04 * t + phase[3:6])
    return poses


@pytest.fixture(scope="session")
def model() -> HandModel:
    return build_hand_model("right")


@pytest.fixture(scope="session")
def true_model(model: HandModel) -> HandModel:
    return perturbed_hand(model, seed=7)
