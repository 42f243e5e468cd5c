"""Kinematic refinement of filled points: no bone longer in the image than it is.

Under an orthographic camera a bone's projected length never exceeds its length times the
image scale. When the clip gives 3D bone lengths and the scale, that product bounds each
bone; otherwise the bound is the longest the bone was ever seen with both its joints
observed (plus :data:`LENGTH_SLACK`). A filled point that stretches a bone past its bound is
pulled toward the other joint of the bone, along the bone, onto the bound; observed points
never move. Bones are visited from the root outward, once.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from handdb.gapfill.gaps import mask_points
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
        ``(T, B) float64``, pixels; ``inf`` where nothing bounds the bone (a read-only
        view when no bound varies from frame to frame).
    """
    parent, child = skeleton.bones.T
    bone = np.take(uv, child, axis=1) - np.take(uv, parent, axis=1)
    squared = bone[..., 0] ** 2 + bone[..., 1] ** 2
    either_missing = np.take(missing, child, axis=1) | np.take(missing, parent, axis=1)
    squared[either_missing] = -1.0
    longest_seen = squared.max(axis=0, initial=-1.0)
    bounds = np.where(longest_seen >= 0, np.sqrt(np.maximum(longest_seen, 0.0)) * LENGTH_SLACK,
                      np.inf)
    n_frames = uv.shape[0]
    if bone_lengths and scale is not None:
        lengths = np.array([bone_lengths.get(name, np.inf) for name in skeleton.bone_names])
        per_frame = np.broadcast_to(np.asarray(scale, dtype=np.float64).reshape(-1, 1),
                                    (n_frames, 1))
        bounds = np.where(np.isfinite(lengths), per_frame * lengths, bounds)
    return np.broadcast_to(bounds, (n_frames, bounds.shape[-1]))


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
    for bones in _bone_rounds(tuple(skeleton.parents)):
        parent, child = skeleton.bones[bones].T
        frame, which = mask_points(np.take(missing, child, axis=1)
                                   | np.take(missing, parent, axis=1))
        parent, child = parent[which], child[which]
        bone = refined[frame, child] - refined[frame, parent]
        length = np.sqrt(bone[:, 0] ** 2 + bone[:, 1] ** 2)
        bound = bounds[frame, bones[which]]
        too_long = length > bound
        frame, parent, child = frame[too_long], parent[too_long], child[too_long]
        bone = bone[too_long] * (bound[too_long] / length[too_long])[:, None]
        moves_child = missing[frame, child]
        moved, kept = np.flatnonzero(moves_child), np.flatnonzero(~moves_child)
        refined[frame[moved], child[moved]] = refined[frame[moved], parent[moved]] + bone[moved]
        refined[frame[kept], parent[kept]] = refined[frame[kept], child[kept]] - bone[kept]
    return refined


@cache
def _bone_rounds(parents: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """Bones (indices into ``Skeleton.bones``) that refinement can pull together, in turn.

    Bones are visited from the root outward: by depth, and among bones of one parent (which
    may pull that parent) one at a time in joint order. Within a round no two bones share
    a joint, so the rounds give what visiting the bones one by one in joint order gives.
    """
    parent = np.asarray(parents)
    child = np.flatnonzero(parent >= 0)
    depth = np.zeros(parent.size, dtype=np.int64)
    for joint in child:
        depth[joint] = depth[parent[joint]] + 1
    sibling_rank = np.array([np.count_nonzero(parent[child[:b]] == parent[c])
                             for b, c in enumerate(child)])
    keys = depth[child] * parent.size + sibling_rank
    return tuple(np.flatnonzero(keys == key) for key in np.unique(keys))
