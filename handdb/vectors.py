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


def _sum_of_products(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a * b`` summed over the last axis from its first component."""
    total = a[..., 0] * b[..., 0]
    for k in range(1, a.shape[-1]):
        total = total + a[..., k] * b[..., k]
    return total


def _short(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether numpy sums the last axis of ``a * b`` one term after another."""
    return a.shape[-1] == b.shape[-1] and 0 < a.shape[-1] < _SEQUENTIAL_TERMS


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.sum(a * b, axis=-1)`` of vectors ``(..., D)``, the other axes broadcast: ``(...)``.

    A sum of ``-0`` terms is ``+0``, as numpy's (adding ``0.0`` changes nothing else).
    """
    if not _short(a, b):
        return np.sum(a * b, axis=-1)
    return _sum_of_products(a, b) + 0.0


def norm(v: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(v, axis=-1)`` of vectors ``(..., D)``: ``(...)``, same unit.

    Squares are never ``-0``, so their sum needs no ``+0``.
    """
    if not _short(v, v):
        return np.linalg.norm(v, axis=-1)
    return np.sqrt(_sum_of_products(v, v))


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of 3-vectors ``(..., 3)``, broadcasting: ``(..., 3)``."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)
