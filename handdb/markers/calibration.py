"""Subject calibration: a hand's bone lengths from its own marker track (Zhao, Chai & Xu, §4).

A few frames with many visible markers are fitted together: the bone lengths, the shape
of the palm and one pose per frame are the unknowns of one nonlinear least-squares problem
solved by Levenberg–Marquardt (:func:`scipy.optimize.least_squares`, ``method="lm"``). LM
takes neither bounds nor a robust loss, so the calibration poses are free of joint limits
and the frames are chosen where markers are plentiful and clean. The residuals are

* every visible marker's error (the model's markers sit on its joints);
* ``(s − s̄) / σ̄``, the paper's pull of the bone lengths towards ``s̄``, the median
  distance between the markers at each bone's ends, weighted by how well that median is
  known: ``σ̄`` is its standard error over the frames that see both ends, and at most
  ``1/sqrt(λ1)``, the paper's fixed weight. A bone seen in every frame is held to its
  measurement; with the paper's fixed weight alone, a thumb the model poses badly traded
  its phalanges for marker error and collapsed them to 0 mm on the real DHG capture;
* the X-ray ratio prior: each phalanx's share of its finger, ``(s_b / Σ_finger s −
  mean_b) / std_b`` (:func:`handdb.lengths.ratios.bone_ratios` of the Chaudhry et al. statistics);
* a weak pull of each palm bone's direction towards the template hand, which fixes the
  rotation that palm shape and root orientation could otherwise trade;
* each bone's length below the shortest of adult hands the plausibility gate admits
  (:func:`handdb.validation.plausibility.length_bounds_mm`), so that a bone no marker pair
  measures (a glove's skin markers skip joints, a tracker hides a joint) cannot be traded
  away to 0 mm for marker error. Only the lower bound: a bone longer than any hand comes
  from markers that measure it so (skin markers named for a joint they are not on), which
  the gate then flags, and holding it short left the glove's fingers far from their
  markers;
* optionally (``limit_weight``), each calibration pose's joint angles beyond the model's
  bounds, so that the shape is one the bounded tracker can pose. Always on, it made the
  synthetic population's hidden joints worse (2.77 to 3.14 mm); :func:`calibrate_reachable`
  turns it on only for a shape the bounded tracker cannot pose (the Qualisys glove's skin
  markers), see ``benchmarks/RESULTS-fitting.md``.

The paper also calibrates each marker's offset from its joint. Here the markers are the
joints (the ``mediapipe21`` marker set), so that freedom goes to the palm's shape instead,
which the template cannot know. Every length is in millimetres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from handdb.checks import mm_per_unit
from handdb.clip import finite_points
from handdb.hand.model import N_DOF, HandModel, forward_kinematics
from handdb.lengths.bone_lengths import BoneLengths
from handdb.lengths.ratios import bone_ratios, table1_ratios
from handdb.markers.solve import MARKER_CUTOFF_MM, SOLVER_TOLERANCE, fit_pose_lsq, initial_pose
from handdb.robust import MEDIAN_EFFICIENCY, nan_median, robust_spread
from handdb.validation.plausibility import length_bounds_mm

#: Calibration frames fitted together.
CALIBRATION_FRAMES = 12

#: Weight λ1 of the pull of bone lengths towards the marker distances, per mm²: the
#: paper's fixed weight, and the least any bone's pull gets.
LENGTH_PRIOR_WEIGHT = 0.05

#: Precision of one marker-to-marker distance beyond the spread the frames show, mm: a
#: bone seen rigidly (no spread) in ``n`` frames is known to about this over ``sqrt(n)``.
MARKER_DISTANCE_FLOOR_MM = 1.0

#: Weight of the X-ray ratio prior, per squared standard deviation: weak, so that a bone
#: both of whose markers are seen is measured by them, while one seldom seen leans on it.
RATIO_PRIOR_WEIGHT = 0.1

#: Weight of the pull of palm bone directions towards the template, per mm² at the joint.
PALM_PRIOR_WEIGHT = 0.01

#: Weight of a calibration pose's excursion beyond the model's joint bounds, mm of marker
#: error per radian, when asked for: a bone of 50-100 mm turned 1 rad past its bound moves
#: its end by about that much. LM takes no bounds, and a shape calibrated in poses the
#: bounded tracker cannot take (a finger twisted 60° at its knuckle) is a shape the tracker
#: cannot fit; chosen a priori, not fitted to any capture.
LIMIT_PRIOR_MM_PER_RAD = 100.0

#: Mean visible-marker distance, mm, beyond which the bounded tracker is taken not to reach a
#: calibrated shape (:func:`bounded_reach`): the marker term's cut-off, past which the
#: robust loss hardly pulls.
REACH_LIMIT_MM = MARKER_CUTOFF_MM

#: Weight of a bone's length below the adult range, per mm: a millimetre short costs as
#: much as a marker 100 mm off in one frame, so the range holds like a bound.
LENGTH_BOUND_WEIGHT = 100.0

#: Finite-difference step of the calibration Jacobian, mm or rad.
JACOBIAN_STEP = 1e-6

#: How the ``bone_lengths`` rows describe their source.
CALIBRATED_SOURCE = "calibrated"


@dataclass(frozen=True)
class Calibration:
    """The result of a subject calibration.

    Attributes
    ----------
    model
        The hand model with the calibrated bone lengths and palm shape (mm).
    frames
        ``(N,) int64`` frames the calibration fitted.
    poses
        ``(N, 33)`` their fitted poses.
    residual
        ``(B,) float64`` root-mean-square marker error at each bone's child joint over
        the calibration frames, mm; NaN where never visible.
    n_frames
        ``(B,) int64`` frames where both markers of each bone were visible (whole clip).
    """

    model: HandModel
    frames: np.ndarray
    poses: np.ndarray
    residual: np.ndarray
    n_frames: np.ndarray


def measured_lengths(model: HandModel, markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Median distance between the markers at each bone's ends.

    Parameters
    ----------
    model
        The hand model whose lengths stand in for bones never seen.
    markers
        ``(T, J, 3)`` mm, NaN where missing.

    Returns
    -------
    lengths : numpy.ndarray
        ``(B,) float64`` mm; the model's length where a bone's markers are never both seen.
    counts : numpy.ndarray
        ``(B,) int64`` frames each median is taken over.
    """
    lengths, counts, _ = _marker_distances(model, markers)
    return lengths, counts


def length_pull_weights(spread: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Weight of each bone's pull towards its measured length, per mm².

    The inverse square of the median's standard error, ``sqrt(pi/2) · sqrt(spread² +
    floor²) / sqrt(n)`` (:data:`MARKER_DISTANCE_FLOOR_MM`), and never below
    :data:`LENGTH_PRIOR_WEIGHT`; that least weight where a bone is never measured.

    Parameters
    ----------
    spread
        ``(B,) float64`` robust standard deviation of each bone's marker distances over the
        frames, mm (NaN where never measured).
    counts
        ``(B,) int64`` frames measuring each bone.
    """
    variance = MEDIAN_EFFICIENCY ** 2 * (np.nan_to_num(spread) ** 2
                                         + MARKER_DISTANCE_FLOOR_MM ** 2)
    with np.errstate(divide="ignore"):
        precision = np.where(counts > 0, counts / variance, 0.0)
    return np.maximum(precision, LENGTH_PRIOR_WEIGHT)


def _marker_distances(model: HandModel, markers: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median, frame count and robust spread (mm) of each bone's marker distances."""
    bones = model.skeleton.bones
    spans = np.linalg.norm(markers[:, bones[:, 1]] - markers[:, bones[:, 0]], axis=-1)
    counts = np.isfinite(spans).sum(axis=0)
    seen = np.where(counts > 0, spans, 0.0)
    lengths = np.where(counts > 0, nan_median(seen), model.bone_lengths)
    return lengths, counts, np.where(counts > 0, robust_spread(seen), np.nan)


def select_frames(visible: np.ndarray, n: int = CALIBRATION_FRAMES) -> np.ndarray:
    """Pick up to ``n`` frames rich in visible markers, spread over the clip.

    Frames are ranked by their number of visible markers; among those at least as rich as
    the ``n``-th richest, ``n`` are taken evenly in time.

    Parameters
    ----------
    visible
        ``(T, J) bool``.
    n
        Number of frames wanted.

    Returns
    -------
    numpy.ndarray
        ``(N,) int64`` increasing frame numbers, ``N = min(n, T)``.
    """
    counts = visible.sum(axis=1)
    n = min(n, len(counts))
    threshold = np.sort(counts)[::-1][n - 1]
    candidates = np.flatnonzero(counts >= threshold)
    picks = np.linspace(0, len(candidates) - 1, n).round().astype(np.int64)
    return candidates[np.unique(picks)]


def default_ratio_prior(model: HandModel) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of each joint's phalanx share, ``(J,)`` each.

    From the X-ray statistics of Chaudhry et al.'s Table 1 (cohort ``all``); NaN for bones
    that are not phalanges.
    """
    return bone_ratios(model.skeleton, table1_ratios())


class _Problem:
    """The calibration's unknowns and residuals, vectorised over leading batch axes.

    Unknowns: the logarithms of the finger bone lengths (so they stay positive, which LM
    cannot otherwise enforce), each palm joint's offset from the wrist (3 numbers; its
    length and direction) and every calibration frame's pose.
    """

    def __init__(self, model: HandModel, markers: np.ndarray,
                 prior_lengths: np.ndarray, pull_weights: np.ndarray,
                 ratio_prior: tuple[np.ndarray, np.ndarray], limit_weight: float = 0.0):
        skeleton = model.skeleton
        self.model = model
        self.limit_weight = limit_weight
        self.visible = finite_points(markers)
        self.target = markers[self.visible]
        self.n_frames = len(markers)
        self.palm = model.palm_joints
        self.palm_bones = np.searchsorted(skeleton.bones[:, 1], self.palm)
        self.finger_bones = np.setdiff1d(np.arange(len(skeleton.bones)), self.palm_bones)
        self.prior_lengths = prior_lengths
        self.pull_scale = np.sqrt(pull_weights)
        self.template_palm = model.rest_directions[self.palm] * prior_lengths[self.palm_bones, None]
        mean, std = ratio_prior
        child = skeleton.bones[:, 1]
        self.ratio_bones = np.flatnonzero(np.isfinite(mean[child]) & (std[child] > 0))
        self.ratio_mean = mean[child][self.ratio_bones]
        self.ratio_std = std[child][self.ratio_bones]
        bounds = length_bounds_mm(skeleton)[child]
        self.length_low = np.nan_to_num(bounds[:, 0], nan=0.0)
        fingers = np.array(skeleton.fingers)[child]
        self.same_finger = (fingers[self.ratio_bones][:, None] == fingers[None, :]) & np.isin(
            np.arange(len(child)), self.ratio_bones)[None, :]
        self.n_shape = len(self.finger_bones) + 3 * len(self.palm)
        self.frame_of_row = np.repeat(np.nonzero(self.visible)[0], 3)

    def pack(self, lengths: np.ndarray, palm: np.ndarray, poses: np.ndarray) -> np.ndarray:
        return np.concatenate([np.log(lengths[self.finger_bones]), palm.ravel(), poses.ravel()])

    def unpack(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        batch = params.shape[:-1]
        n_fingers = len(self.finger_bones)
        palm = params[..., n_fingers:self.n_shape].reshape(batch + (len(self.palm), 3))
        lengths = np.empty(batch + (len(self.model.bone_lengths),))
        lengths[..., self.finger_bones] = np.exp(params[..., :n_fingers])
        lengths[..., self.palm_bones] = np.linalg.norm(palm, axis=-1)
        directions = np.broadcast_to(self.model.rest_directions,
                                     batch + self.model.rest_directions.shape).copy()
        directions[..., self.palm, :] = palm / lengths[..., self.palm_bones, None]
        poses = params[..., self.n_shape:].reshape(batch + (self.n_frames, N_DOF))
        return lengths, directions, poses

    def residuals(self, params: np.ndarray) -> np.ndarray:
        lengths, directions, poses = self.unpack(params)
        joints = forward_kinematics(self.model, poses, lengths[..., None, :],
                                    directions[..., None, :, :])
        markers = (joints[..., self.visible, :] - self.target).reshape(params.shape[:-1] + (-1,))
        pull = self.pull_scale * (lengths - self.prior_lengths)
        palm = params[..., len(self.finger_bones):self.n_shape].reshape(
            params.shape[:-1] + (len(self.palm), 3))
        units = palm / np.linalg.norm(palm, axis=-1, keepdims=True)
        bend = np.sqrt(PALM_PRIOR_WEIGHT) * (
            units * self.prior_lengths[self.palm_bones, None] - self.template_palm)
        totals = (lengths[..., None, :] * self.same_finger).sum(axis=-1)
        shares = lengths[..., self.ratio_bones] / totals
        ratios = np.sqrt(RATIO_PRIOR_WEIGHT) * (shares - self.ratio_mean) / self.ratio_std
        flat_bend = bend.reshape(params.shape[:-1] + (-1,))
        too_short = LENGTH_BOUND_WEIGHT * np.maximum(self.length_low - lengths, 0.0)
        beyond = self.limit_weight * (np.maximum(poses - self.model.upper, 0.0)
                                           - np.maximum(self.model.lower - poses, 0.0))
        flat_beyond = beyond[..., 6:].reshape(params.shape[:-1] + (-1,))
        return np.concatenate([markers, pull, flat_bend, ratios, too_short, flat_beyond],
                              axis=-1)

    def beyond_slopes(self, params: np.ndarray) -> np.ndarray:
        """Derivative of each limit row by its own joint angle, ``(N · 27,)``."""
        poses = self.unpack(params)[2][:, 6:]
        outside = (poses > self.model.upper[6:]) | (poses < self.model.lower[6:])
        return self.limit_weight * outside.ravel().astype(np.float64)

    def jacobian(self, params: np.ndarray) -> np.ndarray:
        """Forward differences in one batched evaluation: pose columns of all frames at once."""
        n_params = len(params)
        probes = np.tile(params, (1 + self.n_shape + N_DOF, 1))
        shape_steps = np.arange(self.n_shape)
        probes[1 + shape_steps, shape_steps] += JACOBIAN_STEP
        for d in range(N_DOF):
            probes[1 + self.n_shape + d, self.n_shape + d::N_DOF] += JACOBIAN_STEP
        values = self.residuals(probes)
        slopes = (values[1:] - values[0]) / JACOBIAN_STEP
        jac = np.zeros((values.shape[1], n_params))
        jac[:, :self.n_shape] = slopes[:self.n_shape].T
        rows = np.arange(len(self.frame_of_row))
        for d in range(N_DOF):
            columns = self.n_shape + self.frame_of_row * N_DOF + d
            jac[rows, columns] = slopes[self.n_shape + d, rows]
        n_angles = N_DOF - 6
        limit_rows = values.shape[1] - self.n_frames * n_angles + np.arange(
            self.n_frames * n_angles)
        angle_columns = (self.n_shape + np.arange(self.n_frames)[:, None] * N_DOF
                         + np.arange(6, N_DOF)[None, :]).ravel()
        jac[limit_rows, :self.n_shape] = 0.0
        jac[limit_rows, angle_columns] = self.beyond_slopes(params)
        return jac


def calibrate(model: HandModel, markers: np.ndarray, *, n_frames: int = CALIBRATION_FRAMES,
              ratio_prior: tuple[np.ndarray, np.ndarray] | None = None,
              limit_weight: float = 0.0) -> Calibration:
    """Estimate bone lengths and palm shape from a marker track by Levenberg–Marquardt.

    Parameters
    ----------
    model
        Starting hand model (its bone lengths only fill bones never seen).
    markers
        ``(T, J, 3)`` markers in mm, NaN where missing; the richest frames need at least
        three visible palm or wrist markers.
    n_frames
        Number of calibration frames.
    ratio_prior
        ``(mean, std)``, ``(J,)`` each: phalanx shares of their finger
        (:func:`handdb.lengths.ratios.bone_ratios`); default :func:`default_ratio_prior`.
    limit_weight
        Weight of the calibration poses' joint angles beyond the model's bounds, mm per
        radian (:data:`LIMIT_PRIOR_MM_PER_RAD` is the measured choice); 0 leaves them free.

    Returns
    -------
    Calibration
    """
    markers = np.asarray(markers, dtype=np.float64)
    visible = finite_points(markers)
    prior_lengths, counts, spread = _marker_distances(model, markers)
    start_model = model.with_geometry(prior_lengths)
    frames = select_frames(visible, n_frames)
    chosen = markers[frames]
    # Poses free of the bounds can twist out of a wrong start; weighed, they must begin in
    # the right valley, so only then are the first poses started again when far off.
    poses = np.stack([fit_pose_lsq(start_model, obs, seen,
                                   initial_pose(start_model, obs, seen,
                                                restart=limit_weight > 0), None)
                      for obs, seen in zip(chosen, visible[frames], strict=True)])
    problem = _Problem(model, chosen, prior_lengths, length_pull_weights(spread, counts),
                       ratio_prior or default_ratio_prior(model), limit_weight)
    palm = model.rest_directions[problem.palm] * prior_lengths[problem.palm_bones, None]
    start = problem.pack(prior_lengths, palm, poses)
    result = least_squares(problem.residuals, start, jac=problem.jacobian, method="lm",
                           x_scale="jac", ftol=SOLVER_TOLERANCE, xtol=SOLVER_TOLERANCE)
    lengths, directions, fitted = problem.unpack(result.x)
    calibrated = model.with_geometry(lengths, directions)
    errors = np.linalg.norm(forward_kinematics(calibrated, fitted) - chosen, axis=-1)
    children = model.skeleton.bones[:, 1]
    seen = visible[frames][:, children]
    n_seen = seen.sum(axis=0)
    squares = np.where(seen, errors[:, children], 0.0) ** 2
    rms = np.full(len(children), np.nan)
    rms[n_seen > 0] = np.sqrt(squares.sum(axis=0)[n_seen > 0] / n_seen[n_seen > 0])
    return Calibration(model=calibrated, frames=frames, poses=fitted, residual=rms,
                       n_frames=counts)


def bounded_reach(calibration: Calibration, markers: np.ndarray) -> float:
    """How close the bounded tracker comes to the calibration frames' markers, mm.

    Each calibration frame is fitted afresh within the joint bounds
    (:func:`~handdb.markers.solve.initial_pose` on the calibrated model); the mean distance
    of its visible markers to their joints, averaged over the frames. The calibration's own
    poses are free of the bounds, so its residual alone cannot tell a shape the tracker can
    pose from one it cannot.

    Parameters
    ----------
    calibration
        The result of :func:`calibrate` (mm).
    markers
        ``(T, J, 3)`` the clip's markers in mm, NaN where missing.
    """
    model = calibration.model
    visible = finite_points(markers)
    distances = []
    for frame in calibration.frames:
        seen = visible[frame]
        pose = initial_pose(model, markers[frame], seen)
        fitted = forward_kinematics(model, pose)[seen]
        distances.append(np.linalg.norm(fitted - markers[frame][seen], axis=-1).mean())
    return float(np.mean(distances))


def calibrate_reachable(model: HandModel, markers: np.ndarray, *,
                        n_frames: int = CALIBRATION_FRAMES,
                        ratio_prior: tuple[np.ndarray, np.ndarray] | None = None
                        ) -> Calibration:
    """:func:`calibrate` with the poses free, bounded only if the tracker cannot reach it.

    When the bounded tracker comes no closer than :data:`REACH_LIMIT_MM` to the calibration
    frames' markers (:func:`bounded_reach`), the shape was bought with poses it cannot take;
    the clip is calibrated again with the poses' angles beyond the bounds weighed
    (:data:`LIMIT_PRIOR_MM_PER_RAD`). Of the two, the one whose worse error, its own fit of
    the calibration frames or the tracker's reach of them, is smaller is kept: a shape the
    tracker reaches is no better if it no longer fits the markers (a tracked hand whose
    palm changes shape over the clip fits no rigid shape in bounded poses).

    Parameters and returns as :func:`calibrate`.
    """
    markers = np.asarray(markers, dtype=np.float64)
    free = calibrate(model, markers, n_frames=n_frames, ratio_prior=ratio_prior)
    free_reach = bounded_reach(free, markers)
    if free_reach <= REACH_LIMIT_MM:
        return free
    bounded = calibrate(model, markers, n_frames=n_frames, ratio_prior=ratio_prior,
                        limit_weight=LIMIT_PRIOR_MM_PER_RAD)
    bounded_error = max(_fit_error(bounded), bounded_reach(bounded, markers))
    return bounded if bounded_error < max(_fit_error(free), free_reach) else free


def _fit_error(calibration: Calibration) -> float:
    """Mean over bones of the calibration's RMS marker error at the bone's child, mm."""
    return float(np.nanmean(calibration.residual))


def calibrated_bone_lengths(calibration: Calibration, units: str) -> BoneLengths:
    """The calibrated bone lengths in the clip's units, with source ``calibrated``.

    Parameters
    ----------
    calibration
        The result of :func:`calibrate` (mm).
    units
        The clip's length unit; lengths and residuals are given in it.
    """
    scale = mm_per_unit(units)
    skeleton = calibration.model.skeleton
    child = skeleton.bones[:, 1]
    lengths = np.full(skeleton.n_joints, np.nan)
    residuals = np.full(skeleton.n_joints, np.nan)
    n_frames = np.zeros(skeleton.n_joints, dtype=np.int64)
    lengths[child] = calibration.model.bone_lengths / scale
    residuals[child] = calibration.residual / scale
    n_frames[child] = calibration.n_frames
    detail = (f"Levenberg-Marquardt subject calibration over {len(calibration.frames)} "
              "marker frames with the X-ray ratio prior (Zhao et al. 2012, section 4)")
    sources = [None if j == skeleton.root else CALIBRATED_SOURCE
               for j in range(skeleton.n_joints)]
    details = [None if source is None else detail for source in sources]
    return BoneLengths(skeleton=skeleton, units=units, lengths=lengths, sources=tuple(sources),
                       details=tuple(details), residuals=residuals, n_frames=n_frames,
                       uncertainty=np.full(skeleton.n_joints, np.nan))
