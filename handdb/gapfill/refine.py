"""Kinematic refinement of filled points: no bone longer in the image than it is.

Under an orthographic camera a bone's projected length never exceeds its length times the
image scale. When the clip gives 3D bone lengths and the scale, that product bounds each
bone; otherwise the bound is the longest the bone was ever seen with both its joints
observed (plus :data:`LENGTH_SLACK`). A filled point that stretches a bone past its bound is
pulled toward the other joint of the bone, along the bone, onto the bound; observed points
never move. Bones are visited from the root outward, once.
"""

from __future__ import annotations

import numpy as np

from handdb.skeletons import Skeleton

#: Slack on the longest projected length a bone was observed with, as a factor.
LENGTH_SLACK = 1.05


def bone_bounds(
    uv: np.ndarray,
    missing: np.ndarray,
    skeleton: Skeleton,
    *,
    bone_lengths: dict[str, float] | None = None,
    scale: float | np.ndarray | None = None,
) -> np.ndarray:
    """Longest allowed projected length of each bone in each frame.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    missing
        ``(T, J) bool``.
    skeleton
        The clip's skeleton; bones in ``skeleton.bones`` order.
    bone_lengths
        3D bone lengths (child joint -> length, clip units), used with ``scale``.
    scale
        Image scale, pixels per clip unit, scalar or ``(T,)``.

    Returns
    -------
    numpy.ndarray
        ``(T, B) float64``, pixels; ``inf`` where nothing bounds the bone.
    """
    parent, child = skeleton.bones.T
    projected = np.linalg.norm(uv[:, child] - uv[:, parent], axis=-1)
    both_seen = ~missing[:, child] & ~missing[:, parent]
    longest_seen = np.max(np.where(both_seen, projected, -np.inf), axis=0)
    bounds = np.where(np.isfinite(longest_seen), longest_seen * LENGTH_SLACK, np.inf)
    bounds = np.broadcast_to(bounds, projected.shape).copy()
    if bone_lengths and scale is not None:
        lengths = np.array([bone_lengths.get(name, np.inf) for name in skeleton.bone_names])
        per_frame = np.broadcast_to(np.asarray(scale, dtype=np.float64).reshape(-1, 1),
                                    (projected.shape[0], 1))
        bounds = np.where(np.isfinite(lengths), per_frame * lengths, bounds)
    return bounds


def refine_bone_lengths(
    uv: np.ndarray,
    missing: np.ndarray,
    skeleton: Skeleton,
    *,
    bone_lengths: dict[str, float] | None = None,
    scale: float | np.ndarray | None = None,
) -> np.ndarray:
    """Pull filled points onto their bones' bounds (see the module docstring).

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels: observed and filled points.
    missing
        ``(T, J) bool``: the filled points, the only ones that may move.
    skeleton, bone_lengths, scale
        As for :func:`bone_bounds`.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: a refined copy.
    """
    bounds = bone_bounds(uv, missing, skeleton, bone_lengths=bone_lengths, scale=scale)
    refined = uv.copy()
    for b, (parent, child) in enumerate(skeleton.bones):
        rows = np.flatnonzero(missing[:, child] | missing[:, parent])
        bone = refined[rows, child] - refined[rows, parent]
        length = np.linalg.norm(bone, axis=-1)
        too_long = length > bounds[rows, b]
        rows = rows[too_long]
        bone = bone[too_long] * (bounds[rows, b] / length[too_long])[:, None]
        moves_child = missing[rows, child]
        refined[rows[moves_child], child] = refined[rows[moves_child], parent] + bone[moves_child]
        refined[rows[~moves_child], parent] = (refined[rows[~moves_child], child]
                                               - bone[~moves_child])
    return refined
