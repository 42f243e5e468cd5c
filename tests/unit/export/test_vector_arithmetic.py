"""The written-out 3-vector arithmetic of ``export.rotations`` is numpy's, bit for bit.

Signed zeros, infinities and NaN included: a joint frame differing from numpy's in one
zero's sign would change a quaternion's bits in the USD layer.
"""

import numpy as np
import pytest

from handdb.export.rotations import _cross, _dot, _norm

SPECIAL = np.array([0.0, -0.0, 1.0, -1.0, 0.5, 3.0, 1e-300, -1e300, np.inf, -np.inf, np.nan])


def _vectors(rng, shape):
    values = rng.normal(size=shape) * np.exp(rng.normal(0.0, 5.0, shape))
    special = rng.random(shape) < 0.4
    values[special] = rng.choice(SPECIAL, special.sum())
    return values


@pytest.mark.parametrize("shape", [(3,), (5000, 3), (40, 15, 3), (1, 21, 3)])
def test_dot_norm_and_cross_are_numpys(shape):
    rng = np.random.default_rng(len(shape))
    a, b = _vectors(rng, shape), _vectors(rng, shape)
    with np.errstate(all="ignore"):
        pairs = [(_dot(a, b), np.sum(a * b, axis=-1)),
                 (_norm(a), np.linalg.norm(a, axis=-1)),
                 (_cross(a, b), np.cross(a, b)),
                 (_cross(a, np.array([0.0, 0.0, 1.0])), np.cross(a, [0.0, 0.0, 1.0]))]
    for got, expected in pairs:
        assert got.shape == expected.shape
        assert np.asarray(got).tobytes() == np.asarray(expected).tobytes()


def test_strided_views_are_numpys():
    frames = _vectors(np.random.default_rng(7), (300, 3, 3))
    axis, other = frames[..., 0], frames[..., 2]
    with np.errstate(all="ignore"):
        assert _dot(axis, other).tobytes() == np.sum(axis * other, axis=-1).tobytes()
        assert _norm(axis).tobytes() == np.linalg.norm(axis, axis=-1).tobytes()
        assert _cross(axis, other).tobytes() == np.cross(axis, other).tobytes()
