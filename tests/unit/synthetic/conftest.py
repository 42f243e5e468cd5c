"""Shared fixtures of the synthetic-hand tests."""

import numpy as np
import pytest

from handdb.synthetic.kinematics import ANGLE_LIMITS, N_ANGLES


@pytest.fixture
def random_angles():
    """``(50, N_ANGLES)`` poses drawn uniformly within the joint limits, radians."""
    rng = np.random.default_rng(12345)
    return rng.uniform(ANGLE_LIMITS[:, 0], ANGLE_LIMITS[:, 1], size=(50, N_ANGLES))


@pytest.fixture
def random_rotations():
    """``(50, 3, 3)`` random proper rotations."""
    rng = np.random.default_rng(678)
    q, r = np.linalg.qr(rng.standard_normal((50, 3, 3)))
    q = q * np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    return q * np.sign(np.linalg.det(q))[:, None, None]
