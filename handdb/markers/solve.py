"""Fit the kinematic hand model to 3D marker tracks, frame by frame (Zhao, Chai & Xu, §5).

The energy of a pose ``q`` at frame ``t`` is ``λm·Em + λc·Ec`` with

* ``Em`` the robust marker term (eq. 4): the mean over model markers of their distance to
  the observed marker, capped at a cut-off ``T`` so that a missing or mislabelled marker
  costs at most ``T``. The paper takes the *nearest* observed marker (its markers are not
  labelled); handdb's markers are labelled, so the labelled correspondence is the default
  and the nearest-neighbour one is kept for comparison.
* ``Ec = ‖q − q̃(t−1)‖`` the smoothness term (eq. 8) against the previous frame's pose.


Every length here is in millimetres; :mod:`handdb.markers.fit` converts clip units.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation, Slerp

from handdb.clip import finite_points
from handdb.errors import ClipDataError, ParameterError, UnknownNameError
from handdb.hand.model import (
    N_DOF,
    ROOT_POSITION,
    ROOT_ROTATION,
    HandModel,
    clip_to_limits,
    forward_kinematics,
)

#: Cut-off of the marker term (eq. 4), millimetres.
MARKER_CUTOFF_MM = 8.0

#: Weights of the marker and smoothness terms in eq. 3 (the paper's λm and λc).
MARKER_WEIGHT = 1.5
SMOOTHNESS_WEIGHT = 0.16

#: Weight λ of the pull towards the interpolated pose in the refinement of eq. 12.
INTERPOLATION_WEIGHT = 0.16

#: Frames in the running median of the filtering step of per-frame IK plus filtering.
FILTER_FRAMES = 5

#: Correspondences between model markers and observed markers in the marker term.
CORRESPONDENCES = ("labelled", "nearest")

#: Pose solvers.
SOLVERS = ("lsq", "pso")

#: Finite-difference step of the least-squares Jacobian (mm for positions, rad for angles).
JACOBIAN_STEP = 1e-6

#: Relative tolerance on cost and step of the least-squares fit, and its evaluation budget.
SOLVER_TOLERANCE = 1e-6
MAX_EVALUATIONS = 200

#: Keeps least-squares starting points strictly inside the joint limits.
LIMIT_MARGIN = 1e-9

#: A visible marker this far from its fitted joint, mm, means the fit is caught in a wrong
#: valley (the robust loss hardly pulls so far a marker): its finger is fitted again from
#: fresh starts.
RECOVERY_DISTANCE_MM = 4.0 * MARKER_CUTOFF_MM

#: Fresh starts of a finger caught far from its markers: its flexion angles at these
#: fractions of their range (0 straight, 1 fully flexed), its other angles at rest.
RESTART_FLEXION = (0.0, 0.5, 0.9)

#: Turns of the aligned rest hand a first pose starts again from when the alignment left the
#: visible markers far off on average: the 24 rotations of the cube (none more than 63° from any
#: orientation, so one start lies in each orientation's valley of the local fit).
ROOT_RESTARTS = tuple(Rotation.create_group("O"))

#: Flexion of the fingers in those starts, as a share of the way from rest (0, straight) to
#: the upper bound (1, fully flexed).
ROOT_RESTART_FLEXION = (0.0, 0.5)


@dataclass(frozen=True)
class SwarmSettings:
    """Particle swarm settings; the defaults are the paper's (§5.3).

    Attributes
    ----------
    n_particles, n_generations
        Swarm size and number of generations per frame.
    cognitive, social
        ``c1`` and ``c2`` of eq. 9.
    position_sigma_mm, angle_sigma_rad
        Standard deviation of the Gaussian perturbation that seeds the swarm around the
        previous frame's pose: root position (mm), and root orientation and joint angles.
    """

    n_particles: int = 48
    n_generations: int = 200
    cognitive: float = 2.8
    social: float = 1.3
    position_sigma_mm: float = 3.0
    angle_sigma_rad: float = 0.08

    @property
    def constriction(self) -> float:
        """The constriction factor ``w`` of eq. 11 for ``φ = c1 + c2``."""
        return constriction_factor(self.cognitive + self.social)

    def sigma(self) -> np.ndarray:
        """Per-parameter perturbation scale, ``(33,) float64``."""
        sigma = np.full(N_DOF, self.angle_sigma_rad)
        sigma[ROOT_POSITION] = self.position_sigma_mm
        return sigma


def constriction_factor(phi: float) -> float:
    """Clerc and Kennedy's constriction factor ``2 / |2 − φ − sqrt(φ² − 4φ)|`` (eq. 11).

    Parameters
    ----------
    phi
        Sum of the cognitive and social coefficients; must exceed 4.
    """
    if phi <= 4.0:
        raise ParameterError(f"the constriction factor needs phi > 4, got {phi}")
    return 2.0 / abs(2.0 - phi - np.sqrt(phi * phi - 4.0 * phi))


def marker_distances(predicted: np.ndarray, observed: np.ndarray, visible: np.ndarray,
                     correspondence: str = "labelled") -> np.ndarray:
    """Distance of each model marker to its observed marker, ``(..., J)``, mm.

    Parameters
    ----------
    predicted
        ``(..., J, 3)`` model marker positions.
    observed
        ``(..., J, 3)`` observed markers (broadcast against ``predicted``); NaN where missing.
    visible
        ``(..., J) bool``, the observed markers present.
    correspondence
        ``"labelled"``: model marker ``i`` pairs with observed marker ``i`` (NaN where that
        one is missing). ``"nearest"``: with the nearest visible observed marker (eq. 4).
    """
    if correspondence == "labelled":
        return np.linalg.norm(predicted - observed, axis=-1)
    if correspondence != "nearest":
        raise UnknownNameError("marker correspondence", str(correspondence), CORRESPONDENCES)
    pairwise = np.linalg.norm(predicted[..., :, None, :] - observed[..., None, :, :], axis=-1)
    pairwise = np.where(visible[..., None, :], pairwise, np.inf)
    return pairwise.min(axis=-1)


def marker_term(predicted: np.ndarray, observed: np.ndarray, visible: np.ndarray,
                cutoff: float = MARKER_CUTOFF_MM, correspondence: str = "labelled") -> np.ndarray:
    """Evaluate the robust marker term ``Em`` of eq. 4, ``(...)``, mm.

    Each model marker costs its distance to its observed marker, at most ``cutoff``; the
    labelled term averages over visible markers, the nearest-neighbour term over all model
    markers (as the paper does).
    """
    capped = np.minimum(marker_distances(predicted, observed, visible, correspondence), cutoff)
    if correspondence == "nearest":
        return capped.mean(axis=-1)
    capped = np.where(visible, capped, 0.0)
    return capped.sum(axis=-1) / np.maximum(visible.sum(axis=-1), 1)


def pose_energy(model: HandModel, pose: np.ndarray, observed: np.ndarray, visible: np.ndarray,
                anchor: np.ndarray, *, anchor_weight: float = SMOOTHNESS_WEIGHT,
                cutoff: float = MARKER_CUTOFF_MM, correspondence: str = "labelled") -> np.ndarray:
    """``λm·Em + λ·‖q − anchor‖`` for poses ``(..., 33)``, giving ``(...)``.

    With ``anchor`` the previous frame's pose this is eq. 3 restricted to markers and
    smoothness (eq. 8); with the interpolated pose and ``anchor_weight = λ`` it is eq. 12.
    ``observed`` ``(..., J, 3)``, ``visible`` ``(..., J)`` and ``anchor`` ``(..., 33)``
    broadcast against the poses.
    """
    predicted = forward_kinematics(model, pose)
    markers = marker_term(predicted, observed, visible, cutoff, correspondence)
    return MARKER_WEIGHT * markers + anchor_weight * np.linalg.norm(pose - anchor, axis=-1)


def particle_swarm(energy: Callable[[np.ndarray], np.ndarray], start: np.ndarray,
                   sigma: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                   settings: SwarmSettings,
                   rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Minimise ``energy`` by constricted particle swarm optimisation (eqs. 9–11).

    Many independent problems run at once: every leading axis of ``start`` is a problem.

    Parameters
    ----------
    energy
        Maps positions ``(..., P, D)`` to energies ``(..., P)``.
    start
        ``(..., D)`` seed of each problem; particle 0 starts on it, the others at Gaussian
        perturbations of it.
    sigma
        ``(D,)`` standard deviation of the perturbations.
    lower, upper
        ``(D,)`` bounds; particles are kept inside.
    settings
        Swarm size, generations and coefficients.
    rng
        Source of the random numbers.

    Returns
    -------
    best : numpy.ndarray
        ``(..., D)`` best position found for each problem.
    best_energy : numpy.ndarray
        ``(...)`` its energy.
    """
    start = np.asarray(start, dtype=np.float64)
    shape = start.shape[:-1] + (settings.n_particles, start.shape[-1])
    noise = rng.standard_normal(shape) * sigma
    noise[..., 0, :] = 0.0
    x = np.clip(start[..., None, :] + noise, lower, upper)
    v = np.zeros_like(x)
    own_best, own_energy = x.copy(), energy(x)
    w = settings.constriction
    for _ in range(settings.n_generations):
        leader = np.take_along_axis(own_best, own_energy.argmin(-1)[..., None, None], axis=-2)
        r1, r2 = rng.random(shape), rng.random(shape)
        v = w * (v + settings.cognitive * r1 * (own_best - x) + settings.social * r2 * (leader - x))
        x = np.clip(x + v, lower, upper)
        f = energy(x)
        better = f < own_energy
        own_best = np.where(better[..., None], x, own_best)
        own_energy = np.where(better, f, own_energy)
    winner = own_energy.argmin(-1)
    best = np.take_along_axis(own_best, winner[..., None, None], axis=-2)[..., 0, :]
    return best, np.take_along_axis(own_energy, winner[..., None], axis=-1)[..., 0]


def fit_pose_pso(model: HandModel, observed: np.ndarray, visible: np.ndarray,
                 start: np.ndarray, anchor: np.ndarray, *,
                 anchor_weight: float = SMOOTHNESS_WEIGHT, cutoff: float = MARKER_CUTOFF_MM,
                 correspondence: str = "labelled", settings: SwarmSettings | None = None,
                 rng: np.random.Generator | None = None) -> np.ndarray:
    """Fit poses by particle swarm, seeded at ``start``; vectorised over leading axes.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    observed, visible
        ``(..., J, 3)`` markers in mm (NaN where missing) and ``(..., J) bool``.
    start, anchor
        ``(..., 33)`` the seed and the pose the smoothness term pulls towards.
    anchor_weight
        Weight of ``‖q − anchor‖`` (λc of eq. 3, or λ of eq. 12).
    cutoff
        Cut-off ``T`` of the marker term, mm.
    correspondence
        ``"labelled"`` or ``"nearest"`` (see :func:`marker_distances`).
    settings
        Swarm settings; default the paper's.
    rng
        Source of random numbers; default seeded with 0.

    Returns
    -------
    numpy.ndarray
        ``(..., 33)`` fitted poses.
    """
    settings = settings or SwarmSettings()
    rng = rng or np.random.default_rng(0)
    observed = np.asarray(observed)[..., None, :, :]
    visible = np.asarray(visible)[..., None, :]
    anchor = np.asarray(anchor)[..., None, :]

    def energy(particles: np.ndarray) -> np.ndarray:
        return pose_energy(model, particles, observed, visible, anchor,
                           anchor_weight=anchor_weight, cutoff=cutoff,
                           correspondence=correspondence)

    best, _ = particle_swarm(energy, clip_to_limits(model, start), settings.sigma(),
                             model.lower, model.upper, settings, rng)
    return best


def _inside_limits(model: HandModel, pose: np.ndarray) -> np.ndarray:
    span = np.where(np.isfinite(model.upper - model.lower), model.upper - model.lower, 1.0)
    return np.clip(pose, model.lower + LIMIT_MARGIN * span, model.upper - LIMIT_MARGIN * span)


def fit_pose_lsq(model: HandModel, observed: np.ndarray, visible: np.ndarray,
                 start: np.ndarray, anchor: np.ndarray | None, *,
                 anchor_weight: float = SMOOTHNESS_WEIGHT,
                 cutoff: float = MARKER_CUTOFF_MM) -> np.ndarray:
    """Fit one pose by bounded robust least squares from ``start``.

    Minimises, within the joint limits, the Cauchy loss ``T²·log(1 + e²/T²)`` of every
    coordinate ``e`` of a visible marker's error (quadratic within the cut-off ``T``,
    logarithmic beyond it: a smooth stand-in for eq. 4 that still pulls a far marker in)
    plus ``(λ/λm)·‖q − anchor‖²``. Markers are labelled.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    observed, visible
        ``(J, 3)`` markers in mm and ``(J,) bool``.
    start
        ``(33,)`` initial pose.
    anchor
        ``(33,)`` pose the regulariser pulls towards, or ``None`` for none.
    anchor_weight
        Weight λ of the regulariser.
    cutoff
        Cut-off ``T``, mm: the scale of the Cauchy loss.

    Returns
    -------
    numpy.ndarray
        ``(33,)`` fitted pose.
    """
    target = observed[visible]
    pull = np.sqrt(anchor_weight / MARKER_WEIGHT)
    steps = np.eye(N_DOF) * JACOBIAN_STEP

    def residuals(poses: np.ndarray) -> np.ndarray:
        markers = (forward_kinematics(model, poses)[..., visible, :] - target)
        markers = markers.reshape(poses.shape[:-1] + (-1,))
        if anchor is None:
            return markers
        return np.concatenate([markers, pull * (poses - anchor)], axis=-1)

    def jacobian(pose: np.ndarray) -> np.ndarray:
        both = residuals(np.concatenate([pose[None], pose + steps]))
        return ((both[1:] - both[0]) / JACOBIAN_STEP).T

    result = least_squares(residuals, _inside_limits(model, start), jac=jacobian,
                           bounds=(model.lower, model.upper), method="trf",
                           loss="cauchy", f_scale=cutoff, x_scale="jac",
                           ftol=SOLVER_TOLERANCE, xtol=SOLVER_TOLERANCE, max_nfev=MAX_EVALUATIONS)
    return result.x


def initial_pose(model: HandModel, observed: np.ndarray, visible: np.ndarray, *,
                 restart: bool = True) -> np.ndarray:
    """Find a first pose for a frame with no predecessor (the paper's ICP plus IK start).

    The rest pose is rigidly aligned to the visible markers (Kabsch, labelled markers; the
    palm's when at least three are visible, else all), then fitted by least squares. A
    finger that fit leaves far from its markers the tracker starts again itself
    (:func:`fit_pose_recovering`); when the visible markers are on average more than
    :data:`RECOVERY_DISTANCE_MM` from their joints, the whole hand is off: the alignment
    was wrong (three skin markers on the back of a hand fix its rotation poorly, and a
    fist's fingers do not unfold together from a flat hand). The fit then starts again from
    the aligned hand turned by each rotation of :data:`ROOT_RESTARTS`, fingers at each
    share of :data:`ROOT_RESTART_FLEXION`; the pose
    of lowest objective is kept.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    observed, visible
        ``(J, 3)`` markers in mm and ``(J,) bool``; at least three visible.
    restart
        Start again from the turned hands when the whole hand is off; ``False`` returns the
        aligned start's fit as it is.

    Returns
    -------
    numpy.ndarray
        ``(33,)`` pose.
    """
    if visible.sum() < 3:
        raise ClipDataError("a first pose needs at least three visible markers")
    rest = forward_kinematics(model, model.rest_pose())
    palm = np.zeros(model.n_joints, dtype=bool)
    palm[[model.skeleton.root, *model.palm_joints]] = True
    use = visible & palm if (visible & palm).sum() >= 3 else visible
    model_centre, data_centre = rest[use].mean(axis=0), observed[use].mean(axis=0)
    rotation, _ = Rotation.align_vectors(observed[use] - data_centre, rest[use] - model_centre)
    pose = fit_pose_lsq(model, observed, visible, _placed(model, rotation, model_centre,
                                                          data_centre, 0.0), None)
    if not restart or _mean_distance(model, pose, observed, visible) <= RECOVERY_DISTANCE_MM:
        return pose
    best = _robust_cost(model, pose, observed, visible, None, 0.0, MARKER_CUTOFF_MM)
    for turn in ROOT_RESTARTS:
        for share in ROOT_RESTART_FLEXION:
            begin = _placed(model, rotation * turn, model_centre, data_centre, share)
            candidate = fit_pose_lsq(model, observed, visible, begin, None)
            cost = _robust_cost(model, candidate, observed, visible, None, 0.0,
                                MARKER_CUTOFF_MM)
            if cost < best:
                pose, best = candidate, cost
    return pose


def _placed(model: HandModel, rotation: Rotation, model_centre: np.ndarray,
            data_centre: np.ndarray, share: float) -> np.ndarray:
    """The rest pose turned about ``model_centre`` and moved onto ``data_centre`` (mm).

    Its root rotation is ``rotation``; its flexion angles sit at ``share`` of the way from
    rest (straight, 0) to their upper bound (fully flexed, 1).
    """
    pose = model.rest_pose()
    flexion = np.array([name.endswith(".flexion") for name in model.dof_names])
    pose[flexion] = share * model.upper[flexion]
    pose[ROOT_ROTATION] = rotation.as_rotvec()
    pose[ROOT_POSITION] = data_centre - rotation.apply(model_centre)
    return pose


def _mean_distance(model: HandModel, pose: np.ndarray, observed: np.ndarray,
                   visible: np.ndarray) -> float:
    """The mean distance from the visible markers to their joints at ``pose``, mm."""
    return float(np.linalg.norm(forward_kinematics(model, pose)[visible] - observed[visible],
                                axis=-1).mean())


def _robust_cost(model: HandModel, pose: np.ndarray, observed: np.ndarray,
                 visible: np.ndarray, anchor: np.ndarray | None, anchor_weight: float,
                 cutoff: float) -> float:
    """The objective :func:`fit_pose_lsq` minimises, at ``pose``."""
    errors = forward_kinematics(model, pose)[visible] - observed[visible]
    cost = float(np.sum(cutoff ** 2 * np.log1p((errors / cutoff) ** 2)))
    if anchor is not None:
        cost += anchor_weight / MARKER_WEIGHT * float(np.sum((pose - anchor) ** 2))
    return cost


def fit_pose_recovering(model: HandModel, observed: np.ndarray, visible: np.ndarray,
                        start: np.ndarray, anchor: np.ndarray | None, *,
                        anchor_weight: float = SMOOTHNESS_WEIGHT,
                        cutoff: float = MARKER_CUTOFF_MM) -> np.ndarray:
    """:func:`fit_pose_lsq`, and fresh starts for every finger left far from its markers.

    A finger that reappears after frames hidden, or that the previous frame left in the
    wrong valley, can end with a visible marker more than :data:`RECOVERY_DISTANCE_MM`
    from its joint, a place the robust loss no longer pulls out of. Each such finger is
    fitted again from the starts of :data:`RESTART_FLEXION`, and the pose of lowest
    objective kept.

    Parameters and returns as :func:`fit_pose_lsq`.
    """
    def fit(begin: np.ndarray) -> np.ndarray:
        return fit_pose_lsq(model, observed, visible, begin, anchor,
                            anchor_weight=anchor_weight, cutoff=cutoff)

    pose = fit(start)
    distance = np.linalg.norm(forward_kinematics(model, pose) - observed, axis=-1)
    far = visible & (distance > RECOVERY_DISTANCE_MM)
    fingers = np.array(model.skeleton.fingers)
    names = np.array(model.dof_names[6:])
    flexion = np.array([name.endswith(".flexion") for name in names])
    for finger in sorted(set(fingers[far])):
        dofs = np.flatnonzero(np.char.startswith(names, f"{finger}_")) + 6
        best = _robust_cost(model, pose, observed, visible, anchor, anchor_weight, cutoff)
        for share in RESTART_FLEXION:
            begin = pose.copy()
            begin[dofs] = np.where(flexion[dofs - 6], model.lower[dofs] + share * (
                model.upper[dofs] - model.lower[dofs]), 0.0)
            candidate = fit(begin)
            cost = _robust_cost(model, candidate, observed, visible, anchor, anchor_weight,
                                cutoff)
            if cost < best:
                pose, best = candidate, cost
    return pose


def constrained_dofs(model: HandModel, visible: np.ndarray) -> np.ndarray:
    """Which degrees of freedom the visible markers of each frame constrain.

    A joint angle moves its bone and every joint beyond it; it is constrained when one of
    those joints' markers is visible. The root's six are constrained by three markers.

    Parameters
    ----------
    model
        The hand model.
    visible
        ``(T, J) bool``.

    Returns
    -------
    numpy.ndarray
        ``(T, 33) bool``.
    """
    parents = model.skeleton.parents
    below = np.eye(model.n_joints, dtype=bool)
    for joint in np.argsort(model.skeleton.depth())[::-1]:
        if parents[joint] >= 0:
            below[parents[joint]] |= below[joint]
    moved = below[model.dof_bone]
    root = np.repeat(visible.sum(axis=1, keepdims=True) >= 3, 6, axis=1)
    return np.concatenate([root, (visible[:, None, :] & moved[None]).any(axis=-1)], axis=1)


def carry_unconstrained(poses: np.ndarray, constrained: np.ndarray) -> np.ndarray:
    """Give each degree of freedom no marker constrains its value from the frames around.

    Between two frames where an angle is constrained it is interpolated linearly; before
    the first and after the last it holds their values. An angle never constrained keeps
    its fitted values (the pull of the previous frame's pose).

    Parameters
    ----------
    poses
        ``(T, 33)`` fitted poses.
    constrained
        ``(T, 33) bool`` (:func:`constrained_dofs`).

    Returns
    -------
    numpy.ndarray
        ``(T, 33)`` poses; ``poses`` is left as it is.
    """
    carried = np.array(poses, dtype=np.float64)
    frames = np.arange(len(poses))
    for dof in range(poses.shape[1]):
        known = constrained[:, dof]
        if known.any() and not known.all():
            carried[~known, dof] = np.interp(frames[~known], frames[known], poses[known, dof])
    return carried


def fit_pose(model: HandModel, observed: np.ndarray, visible: np.ndarray, start: np.ndarray,
             anchor: np.ndarray, *, solver: str = "lsq", anchor_weight: float = SMOOTHNESS_WEIGHT,
             cutoff: float = MARKER_CUTOFF_MM, correspondence: str = "labelled",
             settings: SwarmSettings | None = None,
             rng: np.random.Generator | None = None) -> np.ndarray:
    """Fit one frame's pose with ``solver`` (``"lsq"`` or ``"pso"``); see the two fitters."""
    if solver == "lsq":
        if correspondence != "labelled":
            raise ParameterError("the least-squares fit uses labelled markers only")
        return fit_pose_recovering(model, observed, visible, start, anchor,
                                   anchor_weight=anchor_weight, cutoff=cutoff)
    if solver == "pso":
        return fit_pose_pso(model, observed, visible, start, anchor, anchor_weight=anchor_weight,
                            cutoff=cutoff, correspondence=correspondence, settings=settings,
                            rng=rng)
    raise UnknownNameError("pose solver", str(solver), SOLVERS)


def track(model: HandModel, markers: np.ndarray, *, solver: str = "lsq",
          start: np.ndarray | None = None, correspondence: str = "labelled",
          cutoff: float = MARKER_CUTOFF_MM, settings: SwarmSettings | None = None,
          rng: np.random.Generator | None = None) -> np.ndarray:
    """Fit frames in sequence, each seeded by and smoothed towards the previous one.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    markers
        ``(T, J, 3)`` markers in mm, NaN where missing.
    solver
        ``"lsq"`` or ``"pso"``.
    start
        ``(33,)`` pose before the first frame; default :func:`initial_pose` of frame 0.
    correspondence, cutoff, settings, rng
        As for :func:`fit_pose_pso`.

    Returns
    -------
    numpy.ndarray
        ``(T, 33)`` poses.
    """
    visible = finite_points(markers)
    previous = initial_pose(model, markers[0], visible[0]) if start is None else start
    rng = rng or np.random.default_rng(0)
    poses = np.empty((len(markers), N_DOF))
    for t, (observed, seen) in enumerate(zip(markers, visible, strict=True)):
        previous = fit_pose(model, observed, seen, previous, previous, solver=solver,
                            cutoff=cutoff, correspondence=correspondence,
                            settings=settings, rng=rng)
        poses[t] = previous
    return poses


def interpolate_poses(key_frames: np.ndarray, key_poses: np.ndarray,
                      frames: np.ndarray) -> np.ndarray:
    """Poses between key frames: linear in position and angles, spherical for the root.

    Parameters
    ----------
    key_frames
        ``(K,) int`` increasing frame numbers, ``K >= 2``.
    key_poses
        ``(K, 33)`` their poses.
    frames
        ``(F,)`` frames to interpolate, within ``[key_frames[0], key_frames[-1]]``.

    Returns
    -------
    numpy.ndarray
        ``(F, 33)`` interpolated poses.
    """
    poses = np.stack([np.interp(frames, key_frames, column) for column in key_poses.T], axis=-1)
    slerp = Slerp(key_frames, Rotation.from_rotvec(key_poses[:, ROOT_ROTATION]))
    poses[:, ROOT_ROTATION] = slerp(frames).as_rotvec()
    return poses


def refine_poses(model: HandModel, markers: np.ndarray, guesses: np.ndarray, *,
                 solver: str = "lsq", weight: float = INTERPOLATION_WEIGHT,
                 cutoff: float = MARKER_CUTOFF_MM, settings: SwarmSettings | None = None,
                 rng: np.random.Generator | None = None) -> np.ndarray:
    """Refine interpolated poses to their frames' visible markers (eq. 12).

    Each frame minimises its marker term plus ``weight·‖q − q̂‖`` with ``q̂`` its guess. The
    swarm solves every frame at once (frames × particles); least squares frame by frame.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    markers
        ``(F, J, 3)`` markers in mm, NaN where missing.
    guesses
        ``(F, 33)`` interpolated poses ``q̂``.
    solver
        ``"lsq"`` or ``"pso"``.
    weight
        λ of eq. 12.
    cutoff, settings, rng
        As for :func:`fit_pose_pso`.

    Returns
    -------
    numpy.ndarray
        ``(F, 33)`` refined poses.
    """
    visible = finite_points(markers)
    if solver == "pso":
        return fit_pose_pso(model, markers, visible, guesses, guesses, anchor_weight=weight,
                            cutoff=cutoff, settings=settings, rng=rng)
    return np.stack([
        fit_pose(model, observed, seen, guess, guess, solver=solver, anchor_weight=weight,
                 cutoff=cutoff)
        for observed, seen, guess in zip(markers, visible, guesses, strict=True)
    ])


def filter_and_refine(model: HandModel, markers: np.ndarray, poses: np.ndarray, *,
                      passes: int = 1, window: int = FILTER_FRAMES,
                      weight: float = INTERPOLATION_WEIGHT,
                      cutoff: float = MARKER_CUTOFF_MM) -> np.ndarray:
    """Per-frame inverse kinematics plus filtering (the paper's PFIK+F post-processing).

    Each pass low-passes the pose track (a running median over ``window`` frames of the
    root position and joint angles, which also removes isolated wrong fits) and refits
    every frame to its visible markers, pulled towards the filtered pose as in eq. 12.
    Degrees of freedom no marker constrains thus follow their neighbours in time.

    Parameters
    ----------
    model
        The hand model (bone lengths in mm).
    markers
        ``(T, J, 3)`` markers in mm, NaN where missing.
    poses
        ``(T, 33)`` fitted poses.
    passes
        Number of filter-and-refit passes.
    window
        Frames in the running median.
    weight
        λ of the pull towards the filtered pose (eq. 12).
    cutoff
        Cut-off ``T``, mm.

    Returns
    -------
    numpy.ndarray
        ``(T, 33)`` filtered and refined poses.
    """
    refined = np.asarray(poses, dtype=np.float64)
    for _ in range(passes):
        filtered = median_filter(refined, size=(window, 1), mode="nearest")
        filtered[:, ROOT_ROTATION] = refined[:, ROOT_ROTATION]
        refined = refine_poses(model, markers, filtered, weight=weight, cutoff=cutoff)
    return refined
