"""The written-out vector arithmetic of ``handdb.vectors`` is numpy's, bit for bit.

Signed zeros, infinities and NaN included: a joint frame differing from numpy's in one
zero's sign would change a quaternion's bits in the USD layer.
"""

import numpy as np
import pytest

from handdb.vectors import cross, dot, norm

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
        pairs = [(dot(a, b), np.sum(a * b, axis=-1)),
                 (norm(a), np.linalg.norm(a, axis=-1)),
                 (cross(a, b), np.cross(a, b)),
                 (cross(a, np.array([0.0, 0.0, 1.0])), np.cross(a, [0.0, 0.0, 1.0]))]
    for got, expected in pairs:
        assert got.shape == expected.shape
        assert np.asarray(got).tobytes() == np.asarray(expected).tobytes()


def test_strided_views_are_numpys():
    frames = _vectors(np.random.default_rng(7), (300, 3, 3))
    axis, other = frames[..., 0], frames[..., 2]
    with np.errstate(all="ignore"):
        assert dot(axis, other).tobytes() == np.sum(axis * other, axis=-1).tobytes()
        assert norm(axis).tobytes() == np.linalg.norm(axis, axis=-1).tobytes()
        assert cross(axis, other).tobytes() == np.cross(axis, other).tobytes()


@pytest.mark.parametrize("size", [1, 2, 3, 7, 8, 12])
def test_norm_of_any_length_is_numpys(size):
    values = _vectors(np.random.default_rng(size), (2000, 4, size))
    with np.errstate(all="ignore"):
        assert norm(values).tobytes() == np.linalg.norm(values, axis=-1).tobytes()


@pytest.mark.parametrize("size", [1, 2, 4, 7, 8, 12])
def test_dot_of_any_length_is_numpys(size):
    rng = np.random.default_rng(size)
    a, b = _vectors(rng, (2000, 4, size)), _vectors(rng, (2000, 4, size))
    with np.errstate(all="ignore"):
        assert dot(a, b).tobytes() == np.sum(a * b, axis=-1).tobytes()
