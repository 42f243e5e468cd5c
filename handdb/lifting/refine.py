"""Method ``kinematic-refined``: the hand prior's lift, polished by nonlinear least squares.

Every joint keeps its image point exactly: orthographically ``(x, y) = (u, v) / s`` stays and
only the depth ``z`` moves; through a pinhole the joint slides along its ray, ``Z · r``. The
depths of all frames are then fitted at once (:func:`scipy.optimize.least_squares` with a
sparse Jacobian) to

* bone lengths: ``|P_child − P_parent| − l``, weight 1;
* smoothness: the second difference of every joint's position over time, weight
  :data:`SMOOTHNESS_WEIGHT` (acceleration in clip units per frame²);
* the seed: ``d − d_seed`` at weight :data:`SEED_WEIGHT`, which keeps each bone on the side
  of the image plane the hand prior chose.

The seed clamps every inconsistent bone into the image plane; the refinement spreads the
misfit over lengths and motion instead. It cannot undo a wrong depth sign, which a local
fit does not cross, and costs seconds per clip (``benchmarks/RESULTS-lifting.md``).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import coo_matrix

from handdb.clip import Camera
from handdb.hand.skeletons import Skeleton
from handdb.lifting.kinematic import lift_kinematic
from handdb.lifting.pinhole import camera_rays
from handdb.lifting.result import LiftResult

#: Weight of a joint's acceleration (clip units per frame²) against a bone's length error.
SMOOTHNESS_WEIGHT = 0.02

#: Weight of a joint's depth change from the seed against a bone's length error.
SEED_WEIGHT = 0.05

#: Iteration budget of the solver (function evaluations).
MAX_EVALUATIONS = 15


def _positions(depth: np.ndarray, base: np.ndarray, along: np.ndarray) -> np.ndarray:
    """Joint positions ``base + depth · along``, ``(T, J, 3)``."""
    return base + depth[..., None] * along


def _sparsity(n_frames: int, n_joints: int, bones: np.ndarray) -> coo_matrix:
    """Which depths each residual depends on (rows: lengths, smoothness, seed)."""
    index = np.arange(n_frames * n_joints).reshape(n_frames, n_joints)
    rows, cols = [], []
    n_bones = len(bones)
    length_rows = np.arange(n_frames * n_bones).reshape(n_frames, n_bones)
    for end in (0, 1):
        rows.append(length_rows.ravel())
        cols.append(index[:, bones[:, end]].ravel())
    offset = n_frames * n_bones
    if n_frames > 2:
        smooth_rows = offset + np.arange((n_frames - 2) * n_joints * 3).reshape(
            n_frames - 2, n_joints, 3)
        for lag in (0, 1, 2):
            rows.append(smooth_rows.ravel())
            cols.append(np.repeat(index[lag : n_frames - 2 + lag], 3, axis=-1).ravel())
        offset += (n_frames - 2) * n_joints * 3
    rows.append(offset + index.ravel())
    cols.append(index.ravel())
    rows_all, cols_all = np.concatenate(rows), np.concatenate(cols)
    return coo_matrix((np.ones(len(rows_all)), (rows_all, cols_all)),
                      shape=(offset + n_frames * n_joints, n_frames * n_joints))


def refine_depths(seed: np.ndarray, base: np.ndarray, along: np.ndarray,
                  skeleton: Skeleton, bone_lengths: np.ndarray) -> np.ndarray:
    """Fit every joint's depth parameter to lengths, smoothness and the seed.

    Parameters
    ----------
    seed
        ``(T, J) float64``: starting depth parameter of each joint (no NaN).
    base, along
        ``(T, J, 3) float64``: a joint's position is ``base + depth · along``.
    skeleton
        Gives the bones.
    bone_lengths
        ``(J,) float64``, clip units.

    Returns
    -------
    numpy.ndarray
        ``(T, J) float64``, the fitted depth parameters.
    """
    n_frames, n_joints = seed.shape
    bones = skeleton.bones
    lengths = bone_lengths[bones[:, 1]]

    def residuals(flat: np.ndarray) -> np.ndarray:
        depth = flat.reshape(n_frames, n_joints)
        points = _positions(depth, base, along)
        span = np.linalg.norm(points[:, bones[:, 1]] - points[:, bones[:, 0]], axis=-1)
        parts = [(span - lengths).ravel()]
        if n_frames > 2:
            accel = points[2:] - 2.0 * points[1:-1] + points[:-2]
            parts.append(SMOOTHNESS_WEIGHT * accel.ravel())
        parts.append(SEED_WEIGHT * (depth - seed).ravel())
        return np.concatenate(parts)

    fit = least_squares(residuals, seed.ravel(), method="trf", x_scale="jac",
                        jac_sparsity=_sparsity(n_frames, n_joints, bones),
                        max_nfev=MAX_EVALUATIONS)
    return fit.x.reshape(n_frames, n_joints)


def lift_refined(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                 camera: Camera, *, hand: str) -> LiftResult:
    """Lift with the hand prior, then refine (see the module docstring).

    Parameters are those of :func:`handdb.lifting.lift`. Frames with a missing image point
    are returned as the hand prior lifted them.
    """
    seeded = lift_kinematic(uv, skeleton, bone_lengths, camera, hand=hand)
    complete = np.isfinite(seeded.xyz).all(axis=(1, 2))
    if complete.sum() < 1:
        return seeded
    xyz = seeded.xyz[complete]
    if camera.model == "pinhole":
        along = camera_rays(uv[complete], camera)
        base = np.zeros_like(along)
    else:
        along = np.broadcast_to([0.0, 0.0, 1.0], xyz.shape)
        base = xyz * [1.0, 1.0, 0.0]
    depth = refine_depths(xyz[..., 2], base, along, skeleton, bone_lengths)
    refined = seeded.xyz.copy()
    refined[complete] = _positions(depth, base, along)
    if camera.model != "pinhole":
        refined[complete, :, 2] -= refined[complete, skeleton.root, 2][:, None]
    parent, child = skeleton.bones.T
    inconsistency = np.zeros(seeded.length_inconsistency.shape)
    inconsistency[:, child] = np.abs(
        np.linalg.norm(refined[:, child] - refined[:, parent], axis=-1) - bone_lengths[child])
    return LiftResult(xyz=refined, sign_confidence=seeded.sign_confidence,
                      length_inconsistency=inconsistency, scale=seeded.scale,
                      method="kinematic-refined", mirror_ambiguous=seeded.mirror_ambiguous,
                      mirror_log_odds=seeded.mirror_log_odds, note=seeded.note)

