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

from handdb.compiled import kernel
from handdb.hand.skeletons import Skeleton

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
    longest_seen = _longest_seen(uv, missing, parent, child)
    bounds = np.where(longest_seen >= 0, np.sqrt(np.maximum(longest_seen, 0.0)) * LENGTH_SLACK,
                      np.inf)
    n_frames = uv.shape[0]
    if bone_lengths and scale is not None:
        lengths = np.array([bone_lengths.get(name, np.inf) for name in skeleton.bone_names])
        per_frame = np.broadcast_to(np.asarray(scale, dtype=np.float64).reshape(-1, 1),
                                    (n_frames, 1))
        bounds = np.where(np.isfinite(lengths), per_frame * lengths, bounds)
    return np.broadcast_to(bounds, (n_frames, bounds.shape[-1]))


@kernel
def _longest_seen(
    uv: np.ndarray, missing: np.ndarray, parent: np.ndarray, child: np.ndarray
) -> np.ndarray:
    """Each bone's longest squared length with both its ends observed.

    ``uv`` is ``(T, J, 2)`` pixels (finite where observed), ``missing`` ``(T, J) bool``,
    ``parent`` and ``child`` the bones' joints, ``(B,) int64``. Returns ``(B,) float64``,
    squared pixels, -1 for a bone never seen whole.
    """
    longest = np.full(parent.size, -1.0)
    for b in range(parent.size):
        p, c = parent[b], child[b]
        for frame in range(uv.shape[0]):
            if not (missing[frame, c] or missing[frame, p]):
                bone_x = uv[frame, c, 0] - uv[frame, p, 0]
                bone_y = uv[frame, c, 1] - uv[frame, p, 1]
                longest[b] = max(longest[b], bone_x * bone_x + bone_y * bone_y)
    return longest


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
    order = np.concatenate(_bone_rounds(tuple(skeleton.parents)))
    parent, child = skeleton.bones.T
    _pull_bones(refined, missing, parent[order], child[order], np.take(bounds, order, axis=1))
    return refined


@kernel
def _pull_bones(
    uv: np.ndarray, missing: np.ndarray, parent: np.ndarray, child: np.ndarray,
    bounds: np.ndarray,
) -> None:
    """Pull the filled end of each bone onto its bound, bone after bone, in place.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels; modified.
    missing
        ``(T, J) bool``: the points that may move.
    parent, child
        ``(B,) int64``: the bones' joints, in the order to visit them.
    bounds
        ``(T, B) float64``, pixels: the longest each bone may be in each frame.

    Notes
    -----
    Where a bone with a missing end is longer than its bound, the child is moved along
    the bone onto the bound if it is missing, else the parent.
    """
    for b in range(parent.size):
        p, c = parent[b], child[b]
        for frame in range(uv.shape[0]):
            if not (missing[frame, c] or missing[frame, p]):
                continue
            bone_x = uv[frame, c, 0] - uv[frame, p, 0]
            bone_y = uv[frame, c, 1] - uv[frame, p, 1]
            length = np.sqrt(bone_x * bone_x + bone_y * bone_y)
            if length > bounds[frame, b]:
                ratio = bounds[frame, b] / length
                bone_x, bone_y = bone_x * ratio, bone_y * ratio
                if missing[frame, c]:
                    uv[frame, c, 0] = uv[frame, p, 0] + bone_x
                    uv[frame, c, 1] = uv[frame, p, 1] + bone_y
                else:
                    uv[frame, p, 0] = uv[frame, c, 0] - bone_x
                    uv[frame, p, 1] = uv[frame, c, 1] - bone_y


@cache
def _bone_rounds(parents: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """The order refinement visits the bones in (indices into ``Skeleton.bones``), by rounds.

    Bones are visited from the root outward: by depth, and among bones of one parent (which
    may pull that parent) one at a time in joint order. Within a round no two bones share
    a joint, so the order within a round does not matter.
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
