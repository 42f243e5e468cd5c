"""Small-vector arithmetic over the last axis, written out component by component.

numpy's reductions over an axis of two or three (``np.sum``, ``np.linalg.norm``) and
``np.cross`` cost several times the arithmetic they do. These give the same values to the
last bit: the components are summed from the first, starting from ``+0`` as numpy's sum
of fewer than eight terms does, and crossed as ``np.cross`` does (each product, then the
difference).
"""

from __future__ import annotations

import numpy as np

#: numpy sums fewer terms than this one after another (its pairwise sum's block).
_SEQUENTIAL_TERMS = 8


def _sum_of_squares(v: np.ndarray) -> np.ndarray:
    total = v[..., 0] * v[..., 0]
    for k in range(1, v.shape[-1]):
        total = total + v[..., k] * v[..., k]
    return total


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.sum(a * b, axis=-1)`` of 3-vectors ``(..., 3)``, broadcasting: ``(...)``.

    A sum of ``-0`` terms is ``+0``, as numpy's (adding ``0.0`` changes nothing else).
    """
    return ((a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]) + a[..., 2] * b[..., 2]) + 0.0


def norm(v: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(v, axis=-1)`` of vectors ``(..., D)``: ``(...)``, same unit.

    Squares are never ``-0``, so their sum needs no ``+0``.
    """
    if not 0 < v.shape[-1] < _SEQUENTIAL_TERMS:
        return np.linalg.norm(v, axis=-1)
    return np.sqrt(_sum_of_squares(v))


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of 3-vectors ``(..., 3)``, broadcasting: ``(..., 3)``."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)
