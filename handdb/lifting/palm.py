"""The palm's depth signs: its near-rigid, near-planar joints fit a plane.

Of the sign patterns of the palm's bones, the one whose joints fit a plane best is kept,
with its mirror image (every sign flipped: the palm tilted the other way, which fits the
same plane mirrored) as the palm's only other state. The search runs as one compiled
kernel (numba) over the frames.
"""

from __future__ import annotations

import itertools

import numpy as np

from handdb.compiled import kernel
from handdb.hand.layout import HandLayout
from handdb.hand.skeletons import Skeleton
from handdb.lifting.geometry import path_lists, path_matrix

#: Ridge added to the palm plane's normal equations (clip units²) so that a palm seen
#: edge-on, its joints on one image line, still has a plane.
PLANE_RIDGE = 1e-9


def palm_signs(xy: np.ndarray, abs_dz: np.ndarray, skeleton: Skeleton,
               layout: HandLayout) -> np.ndarray:
    """Sign pattern of the palm's bones that best fits a plane, per frame.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.
    skeleton, layout
        The clip's skeleton, its palm and fingers.

    Returns
    -------
    numpy.ndarray
        ``(T, P) float64`` of ±1 for ``layout.palm_bones``; the mirror pattern (all signs
        flipped) fits exactly as well and is the palm's other state. Patterns are
        oriented so that the palm's tilt changes continuously from frame to frame
        (:func:`continuity_signs`): a frame's state 0 continues the previous one's.
    """
    bones = layout.palm_bones
    joints = np.concatenate([[skeleton.root], bones])
    to_depth = path_matrix(skeleton)[np.ix_(joints, bones)]             # (Q, P)
    # Half the patterns suffice: a pattern and its mirror fit the plane equally well.
    combos = np.array(list(itertools.product((1.0, -1.0), repeat=len(bones) - 1)))
    combos = np.concatenate([np.ones((len(combos), 1)), combos], axis=1)
    spans = np.nan_to_num(abs_dz[:, bones])[:, None, :] * to_depth       # (T, Q, P)
    # The bones each joint's depth sums, in bone order: a sum over all of them would add
    # mostly zeros.
    paths, path_lengths = path_lists(to_depth > 0)
    best = np.empty(len(xy), dtype=np.int64)
    _best_plane_patterns(np.nan_to_num(xy[:, joints]), spans, combos, paths, path_lengths,
                         PLANE_RIDGE, best)
    depths = np.einsum("tqp,tp->tq", spans, combos[best])
    return combos[best] * continuity_signs(depths)[:, None]


def continuity_signs(depths: np.ndarray) -> np.ndarray:
    """Signs that make a sequence of palm poses, each known up to its mirror, continuous.

    Parameters
    ----------
    depths
        ``(T, Q) float64``: depth of each palm joint relative to the root, per frame, with
        an arbitrary overall sign.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64`` of ±1 such that consecutive signed palm depths never point apart
        (their dot product is not negative).
    """
    turn = np.ones(len(depths))
    turn[1:] = np.where(np.sum(depths[1:] * depths[:-1], axis=-1) < 0, -1.0, 1.0)
    return np.cumprod(turn)


@kernel
def _best_plane_patterns(xy, spans, combos, paths, path_lengths, ridge, best):
    """Fill ``best`` ``(T,)`` with the pattern whose joint depths fit a plane best.

    ``xy`` is ``(T, Q, 2)``, the palm joints in the image plane; ``spans`` ``(T, Q, P)``
    the depth each bone adds to each joint, nonzero only for the bones
    ``paths[q, :path_lengths[q]]`` (``(Q, P)`` and ``(Q,)``); ``combos`` ``(C, P)`` the
    sign patterns. The misfit of depths ``z`` is ``z·z − bᵀ M⁻¹ b`` with
    ``M = DᵀD + ridge·I`` and ``b = Dᵀz``, ``D`` the design ``[x, y, 1]``. The sums run
    over the joints for all patterns at once, so that the loop over the patterns is
    innermost and vectorises.
    """
    n_frames, n_joints, _ = spans.shape
    n_combos = combos.shape[0]
    signs = np.ascontiguousarray(combos.T)                               # (P, C)
    normal, inverse = np.empty((3, 3)), np.empty((3, 3))
    z, zz, bx = np.empty(n_combos), np.empty(n_combos), np.empty(n_combos)
    by, b1 = np.empty(n_combos), np.empty(n_combos)
    for t in range(n_frames):
        _plane_inverse(xy[t], ridge, normal, inverse)
        zz[:] = 0.0
        bx[:] = 0.0
        by[:] = 0.0
        b1[:] = 0.0
        for q in range(n_joints):
            z[:] = 0.0
            for step in range(path_lengths[q]):
                p = paths[q, step]
                span = spans[t, q, p]
                for c in range(n_combos):
                    z[c] += span * signs[p, c]
            x, y = xy[t, q, 0], xy[t, q, 1]
            for c in range(n_combos):
                zz[c] += z[c] * z[c]
                bx[c] += x * z[c]
                by[c] += y * z[c]
                b1[c] += z[c]
        lowest = np.inf
        for c in range(n_combos):
            fitted = (bx[c] * (inverse[0, 0] * bx[c] + inverse[0, 1] * by[c]
                               + inverse[0, 2] * b1[c])
                      + by[c] * (inverse[1, 0] * bx[c] + inverse[1, 1] * by[c]
                                 + inverse[1, 2] * b1[c])
                      + b1[c] * (inverse[2, 0] * bx[c] + inverse[2, 1] * by[c]
                                 + inverse[2, 2] * b1[c]))
            if zz[c] - fitted < lowest:
                lowest = zz[c] - fitted
                best[t] = c


@kernel
def _plane_inverse(xy, ridge, normal, inverse):
    """Write ``(DᵀD + ridge·I)⁻¹`` to ``inverse``, ``D = [x, y, 1]`` of ``xy`` ``(Q, 2)``.

    ``normal`` ``(3, 3)`` is scratch space for ``DᵀD + ridge·I``.
    """
    normal[:] = 0.0
    for q in range(xy.shape[0]):
        x, y = xy[q, 0], xy[q, 1]
        normal[0, 0] += x * x
        normal[0, 1] += x * y
        normal[0, 2] += x
        normal[1, 1] += y * y
        normal[1, 2] += y
    normal[1, 0], normal[2, 0], normal[2, 1] = normal[0, 1], normal[0, 2], normal[1, 2]
    normal[2, 2] = xy.shape[0]
    for k in range(3):
        normal[k, k] += ridge
    _invert_3x3(normal, inverse)


@kernel
def _invert_3x3(m, out):
    """Write the inverse of the 3×3 matrix ``m`` to ``out`` (adjugate over determinant)."""
    for i in range(3):
        for j in range(3):
            a, b = (j + 1) % 3, (j + 2) % 3
            c, d = (i + 1) % 3, (i + 2) % 3
            out[i, j] = m[a, c] * m[b, d] - m[a, d] * m[b, c]
    det = m[0, 0] * out[0, 0] + m[0, 1] * out[1, 0] + m[0, 2] * out[2, 0]
    for i in range(3):
        for j in range(3):
            out[i, j] /= det
