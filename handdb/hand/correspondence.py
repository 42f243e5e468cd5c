"""Convert joint arrays between skeleton presets where joints correspond.

Joints correspond when they share a canonical name (``index_pip`` in ``mediapipe21`` is
``index_pip`` in ``dhg22`` and feature point 5 of ``thesis21``). Joints of the target that
the source lacks come out as NaN.
"""

from __future__ import annotations

import numpy as np

from handdb.hand.skeletons import Skeleton


def correspondence(source: Skeleton, target: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Return index pairs of the joints the two skeletons share.

    Returns
    -------
    src, dst
        ``(K,) int64`` each: joint ``source.joints[src[k]]`` is ``target.joints[dst[k]]``.
    """
    shared = [(i, target.joints.index(name)) for i, name in enumerate(source.joints)
              if name in target.joints]
    if not shared:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    src, dst = np.array(shared, dtype=np.int64).T
    return src, dst


def convert_points(points: np.ndarray, source: Skeleton, target: Skeleton) -> np.ndarray:
    """Map per-joint values from ``source`` to ``target`` order.

    Parameters
    ----------
    points
        ``(..., J_source, D)`` values (coordinates, or ``D = 1`` for scalars).
    source, target
        The skeletons the joint axis is ordered by.

    Returns
    -------
    numpy.ndarray
        ``(..., J_target, D) float64``; NaN for target joints the source lacks.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.shape[-2] != source.n_joints:
        raise ValueError(
            f"points have {points.shape[-2]} joints on axis -2, skeleton '{source.name}' "
            f"has {source.n_joints}"
        )
    out = np.full(points.shape[:-2] + (target.n_joints, points.shape[-1]), np.nan)
    src, dst = correspondence(source, target)
    out[..., dst, :] = points[..., src, :]
    return out
