"""Bone lengths fitted to noisy 3D frames by robust least squares.

In the spirit of the subject calibration of Zhao, Chai & Xu (SCA 2012, section 4), which
fits a hand's skeletal sizes to 3D calibration frames by nonlinear least squares with a
prior on the sizes, but for joint positions (a tracker's 3D output, or markers placed on
the joints): each bone's length is then observed directly in every frame in which both
of its joints are present, and no pose needs fitting. The lengths ``s`` minimise

    sum over frames t and bones b of  rho(((d_tb - sqrt(s_b^2 + 2 sigma_b^2)) / sigma_b)^2)
    + weight * sum over phalanges k of  ((s_k / S_f(k) - mu_k) / std_k)^2

where ``d_tb`` is the bone's length in frame ``t`` and ``sigma_b`` the robust spread of
those lengths (1.4826 median absolute deviation). Noise on the two ends makes a bone look
longer, not shorter: with isotropic noise of variance ``sigma^2`` per axis on the
difference of its ends, ``E[d^2] = s^2 + 3 sigma^2`` and ``d`` spreads by about
``sigma`` along the bone, so ``d`` centres on ``sqrt(s^2 + 2 sigma^2)``; a plain median
of ``d`` keeps that bias. ``rho`` is a robust loss (Cauchy by default: a frame where a
joint jumped barely counts), folded into the residuals so that
:func:`scipy.optimize.least_squares` leaves the prior quadratic; the second term is the
X-ray prior: the relative length of each phalanx within its finger (``S_f`` the sum of the
finger's phalanges) should lie near the mean ratio ``mu_k`` of Chaudhry et al., with
their spread ``std_k``. ``weight`` is the prior's worth in frames: with ``weight=1`` the
ratios count as much as one more frame of every phalanx.

:mod:`handdb.subject_calibration` is the paper's full method (poses and lengths fitted
together through forward kinematics); this one needs no hand model and suits any preset.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from scipy import sparse
from scipy.optimize import least_squares

from handdb.ratios import bone_ratios
from handdb.skeletons import Skeleton

#: Scale from the median absolute deviation to the standard deviation of a normal.
MAD_TO_SIGMA = 1.4826

#: Robust losses rho(z^2) of the per-frame residuals, as scipy.optimize.least_squares
#: names them. They are applied to the frames only, so the prior stays quadratic.
ROBUST_LOSSES: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "cauchy": np.log1p,
    "soft_l1": lambda z2: 2.0 * (np.sqrt(1.0 + z2) - 1.0),
    "linear": lambda z2: z2,
}

#: The loss of the per-frame residuals unless the caller names another.
DEFAULT_LOSS = "cauchy"

#: The per-frame length of a bone centres on sqrt(s^2 + NOISE_BIAS * sigma^2).
NOISE_BIAS = 2.0

#: Floor of a bone's robust spread, relative to its median length, so that exact
#: (noise-free) data do not divide by zero.
MIN_RELATIVE_SPREAD = 1e-6


@dataclass(frozen=True)
class CalibrationResult:
    """Bone lengths fitted to 3D frames.

    Attributes
    ----------
    lengths
        ``(J,) float64``, input units: length of the bone ending at each joint; NaN for
        the root and for bones never observed.
    median
        ``(J,) float64``: the per-bone median over frames, where the fit starts (the
        baseline the fit improves on).
    residuals
        ``(J,) float64``, input units: median absolute difference between a bone's
        per-frame length and the length the fit expects to see (its fitted length
        widened by the noise, see the module docstring).
    n_frames
        ``(J,) int64``: frames in which the bone was observed.
    prior_deviation
        ``(J,) float64``: how far each phalanx's fitted relative length lies from the
        X-ray mean, in X-ray standard deviations; NaN where there is no prior.
    converged
        Whether the optimiser reported convergence.
    """

    lengths: np.ndarray
    median: np.ndarray
    residuals: np.ndarray
    n_frames: np.ndarray
    prior_deviation: np.ndarray
    converged: bool


def frame_bone_lengths(positions: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Length of every bone in every frame.

    Parameters
    ----------
    positions
        ``(T, J, D) float64`` joint positions (``D`` = 3, or 2 for image points), any
        unit; NaN where missing.
    skeleton
        The skeleton of the joint axis.

    Returns
    -------
    np.ndarray
        ``(T, J) float64``: length of the bone ending at each joint, in the unit of
        ``positions``; NaN for the root and where either end is missing.
    """
    lengths = np.full(positions.shape[:2], np.nan)
    parent, child = skeleton.bones.T
    lengths[:, child] = np.linalg.norm(positions[:, child] - positions[:, parent], axis=-1)
    return lengths


def _same_finger(skeleton: Skeleton, members: np.ndarray) -> np.ndarray:
    """``(J, J) bool``: row ``k`` selects the members on the finger of joint ``k``."""
    fingers = np.array(skeleton.fingers)
    return (fingers[:, None] == fingers[None, :]) & members[:, None] & members[None, :]


def calibrate_bone_lengths(
    xyz: np.ndarray,
    skeleton: Skeleton,
    ratios: pa.Table | None = None,
    weight: float = 1.0,
    loss: str = DEFAULT_LOSS,
) -> CalibrationResult:
    """Estimate a subject's bone lengths from noisy 3D frames by robust least squares.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions in any length unit, NaN where missing.
    skeleton
        The skeleton of the joint axis.
    ratios
        Table ``joint_ratios`` whose cohort ``all`` regularises the phalanges; ``None``
        fits the frames alone.
    weight
        Worth of the ratio prior, in frames (see the module docstring); ``>= 0``.
    loss
        Robust loss of the per-frame residuals: ``cauchy``, ``soft_l1``, or ``linear``
        for plain least squares (see :data:`ROBUST_LOSSES`).

    Returns
    -------
    CalibrationResult
        Lengths in the units of ``xyz``, with per-bone residuals.
    """
    if weight < 0:
        raise ValueError(f"the prior's weight must be >= 0, got {weight}")
    if loss not in ROBUST_LOSSES:
        raise ValueError(f"unknown loss '{loss}'; losses: {', '.join(ROBUST_LOSSES)}")
    rho = ROBUST_LOSSES[loss]
    per_frame = frame_bone_lengths(xyz, skeleton)
    observed = np.isfinite(per_frame)
    n_frames = observed.sum(axis=0)
    fitted = n_frames > 0
    median = np.full(skeleton.n_joints, np.nan)
    median[fitted] = np.nanmedian(per_frame[:, fitted], axis=0)
    spread = MAD_TO_SIGMA * np.nanmedian(np.abs(per_frame[:, fitted] - median[fitted]), axis=0)
    sigma = np.maximum(spread, MIN_RELATIVE_SPREAD * median[fitted])

    frame, bone = np.nonzero(observed[:, fitted])
    data = per_frame[:, fitted][frame, bone]
    no_prior = np.full(skeleton.n_joints, np.nan)
    mean, std = (no_prior, no_prior) if ratios is None else bone_ratios(skeleton, ratios)
    has_prior = fitted & np.isfinite(mean) & (np.nan_to_num(std) > 0)
    finger_sum = _same_finger(skeleton, has_prior)[np.ix_(has_prior, fitted)]
    prior = has_prior[fitted]
    prior_scale = np.sqrt(weight) / std[has_prior]

    def residuals(lengths: np.ndarray) -> np.ndarray:
        expected = np.sqrt(lengths[bone] ** 2 + NOISE_BIAS * sigma[bone] ** 2)
        z = (data - expected) / sigma[bone]
        frames = np.sign(z) * np.sqrt(rho(z**2))
        relative = lengths[prior] / (finger_sum @ lengths)
        return np.concatenate([frames, (relative - mean[has_prior]) * prior_scale])

    sparsity = sparse.vstack([
        sparse.csr_matrix((np.ones(data.size), (np.arange(data.size), bone)),
                          shape=(data.size, fitted.sum())),
        sparse.csr_matrix(finger_sum),
    ])
    solution = least_squares(residuals, median[fitted], bounds=(0.0, np.inf), x_scale="jac",
                             jac_sparsity=sparsity)
    lengths = np.full(skeleton.n_joints, np.nan)
    lengths[fitted] = solution.x
    deviation = np.full(skeleton.n_joints, np.nan)
    deviation[has_prior] = (solution.x[prior] / (finger_sum @ solution.x)
                            - mean[has_prior]) / std[has_prior]
    residual = np.full(skeleton.n_joints, np.nan)
    expected = np.sqrt(solution.x ** 2 + NOISE_BIAS * sigma ** 2)
    residual[fitted] = np.nanmedian(np.abs(per_frame[:, fitted] - expected), axis=0)
    return CalibrationResult(
        lengths=lengths,
        median=median,
        residuals=residual,
        n_frames=n_frames.astype(np.int64),
        prior_deviation=deviation,
        converged=bool(solution.success),
    )
