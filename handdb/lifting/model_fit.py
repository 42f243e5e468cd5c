"""Lifting by fitting the 33-DoF hand model to the 2D track (method ``model-fit``).

The marker fit of Zhao, Chai & Xu with reprojection in place of 3D distance: frame by
frame, the pose (and, for a scaled-orthographic camera, the scale) that puts the model's
joints on the tracked points, within the joint limits, with the smoothness term of eq. 8
against the previous frame. The bone lengths are the clip's; the model's joint limits and
the smoothness term choose among the depth signs a single view leaves open.

Cameras: ``pinhole`` projects ``u = fx·x/z + cx, v = fy·y/z + cy``; ``orthographic``
projects ``u = s·x, v = s·y`` with ``s`` fitted per frame and the root at ``z = 0``, the
convention of :class:`~handdb.lifting.result.LiftResult`.

Every joint gets a position, tracked or not: the model fills joints without an image point.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from handdb.clip import Camera, finite_points
from handdb.errors import ClipDataError
from handdb.hand.anatomy import AXES
from handdb.hand.model import (
    N_DOF,
    ROOT_POSITION,
    ROOT_ROTATION,
    HandModel,
    build_hand_model,
    forward_kinematics,
)
from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import Skeleton
from handdb.lifting.methods import MODEL_FIT
from handdb.lifting.result import LiftResult
from handdb.markers.solve import MARKER_WEIGHT, MAX_EVALUATIONS, SMOOTHNESS_WEIGHT, SOLVER_TOLERANCE

#: Name of the method in the lifting registry.
METHOD = MODEL_FIT

#: Cut-off of the robust reprojection term, pixels (the 2D counterpart of eq. 4's 8 mm).
REPROJECTION_CUTOFF_PX = 8.0

#: Image points a frame needs to be fitted; sparser frames keep the previous pose.
MIN_POINTS = 4

#: Index of the log-scale parameter appended to the pose for orthographic cameras.
LOG_SCALE = N_DOF

#: Starts tried on the first frame: the palm turned towards or away from the camera, tilted
#: about the camera's x and y axes (degrees), and every finger joint flexed by each angle.
FIRST_FRAME_TURNS_DEG = (0.0, 180.0)
FIRST_FRAME_TILTS_DEG = (-30.0, 30.0)
FIRST_FRAME_ROLLS_DEG = (-20.0, 20.0)
FIRST_FRAME_FLEXION_DEG = (0.0, 35.0)

#: A relaxed hand, every finger joint flexed this much (degrees), and the weight of a weak
#: pull of the joint angles towards it (per rad², against pixels²): among poses that
#: project alike (a finger bent towards the camera or away), it prefers the natural one.
RELAXED_FLEXION_DEG = 20.0
RELAXED_WEIGHT = 4.0

#: Finite-difference step of the Jacobian.
JACOBIAN_STEP = 1e-6


def _model_lengths(skeleton: Skeleton, bone_lengths: np.ndarray,
                   hand: str) -> tuple[HandModel, float]:
    """The hand model on the clip's skeleton with its bone lengths, in template millimetres.

    Returns the model and ``k``, template millimetres per clip unit (the median ratio of
    the average hand's lengths to the clip's).
    """
    template = mean_shape()
    reference = template.bone_lengths(skeleton)
    known = np.isfinite(reference) & np.isfinite(bone_lengths) & (bone_lengths > 0)
    k = float(np.median(reference[known] / bone_lengths[known]))
    shape = template.with_bone_lengths(skeleton, np.where(known, bone_lengths * k, np.nan))
    return build_hand_model(hand, skeleton=skeleton, shape=shape), k


def _project(points: np.ndarray, params: np.ndarray, camera: Camera) -> np.ndarray:
    """Image points of model joints ``(..., J, 3)``, ``(..., J, 2)`` pixels."""
    if camera.model == "pinhole":
        depth = points[..., 2]
        return np.stack([camera.fx * points[..., 0] / depth + camera.cx,
                         camera.fy * points[..., 1] / depth + camera.cy], axis=-1)
    return np.exp(params[..., LOG_SCALE])[..., None, None] * points[..., :2]


def _positions(model: HandModel, params: np.ndarray, camera: Camera) -> np.ndarray:
    pose = params[..., :N_DOF].copy()
    if camera.model == "orthographic":
        pose[..., 2] = 0.0
    return forward_kinematics(model, pose)


def _relaxed_pose(model: HandModel) -> np.ndarray:
    """Parameters of the relaxed hand: every flexion at :data:`RELAXED_FLEXION_DEG`."""
    relaxed = np.zeros(N_DOF + 1)
    relaxed[6 + np.flatnonzero(model.dof_axis == AXES.index("flexion"))] = np.radians(
        RELAXED_FLEXION_DEG)
    return relaxed


def _fit_frame(model: HandModel, camera: Camera, uv: np.ndarray, seen: np.ndarray,
               start: np.ndarray, anchor: np.ndarray | None) -> tuple[np.ndarray, float]:
    """Fit one frame's parameters; return them and the final cost."""
    free = np.arange(N_DOF + 1)
    free = free[free != (2 if camera.model == "orthographic" else LOG_SCALE)]
    lower = np.append(model.lower, -np.inf)[free]
    upper = np.append(model.upper, np.inf)[free]
    target = uv[seen]
    pull = np.sqrt(SMOOTHNESS_WEIGHT / MARKER_WEIGHT)
    relaxed = _relaxed_pose(model)
    joint_angles = np.flatnonzero(free >= 6)
    joint_angles = joint_angles[free[joint_angles] < N_DOF]

    def full(x: np.ndarray) -> np.ndarray:
        params = np.broadcast_to(start, x.shape[:-1] + start.shape).copy()
        params[..., free] = x
        return params

    def residuals(x: np.ndarray) -> np.ndarray:
        params = full(x)
        image = _project(_positions(model, params, camera), params, camera)
        errors = (image[..., seen, :] - target).reshape(x.shape[:-1] + (-1,))
        natural = np.sqrt(RELAXED_WEIGHT) * (x[..., joint_angles] - relaxed[free[joint_angles]])
        if anchor is None:
            return np.concatenate([errors, natural], axis=-1)
        return np.concatenate([errors, natural, pull * (x - anchor[free])], axis=-1)

    steps = np.eye(len(free)) * JACOBIAN_STEP

    def jacobian(x: np.ndarray) -> np.ndarray:
        values = residuals(np.concatenate([x[None], x + steps]))
        return ((values[1:] - values[0]) / JACOBIAN_STEP).T

    x0 = np.clip(start[free], lower + 1e-9, upper - 1e-9)
    result = least_squares(residuals, x0, jac=jacobian, bounds=(lower, upper), method="trf",
                           loss="cauchy", f_scale=REPROJECTION_CUTOFF_PX, x_scale="jac",
                           ftol=SOLVER_TOLERANCE, xtol=SOLVER_TOLERANCE,
                           max_nfev=MAX_EVALUATIONS)
    return full(result.x), float(result.cost)


def _first_frame(model: HandModel, camera: Camera, uv: np.ndarray,
                 seen: np.ndarray) -> np.ndarray:
    """Fit the first frame from several root orientations and keep the best fit."""
    rest = forward_kinematics(model, model.rest_pose())
    skeleton = model.skeleton
    root, middle = skeleton.root, skeleton.index("middle_mcp")
    centre = uv[seen].mean(axis=0)
    spread = np.linalg.norm(uv[seen] - centre, axis=-1).mean()
    model_spread = np.linalg.norm(rest - rest.mean(axis=0), axis=-1).mean()
    start = np.zeros(N_DOF + 1)
    if camera.model == "pinhole":
        depth = camera.fx * model_spread / spread
        start[ROOT_POSITION] = [(centre[0] - camera.cx) * depth / camera.fx,
                                (centre[1] - camera.cy) * depth / camera.fy, depth]
    else:
        start[LOG_SCALE] = np.log(spread / model_spread)
        start[:2] = centre / np.exp(start[LOG_SCALE])
    pointing = (uv[middle] - uv[root]) if seen[[root, middle]].all() else np.array([0.0, -1.0])
    in_plane = np.degrees(np.arctan2(pointing[0], -pointing[1]))
    flexion = 6 + np.flatnonzero(model.dof_axis == AXES.index("flexion"))
    best, best_cost = start, np.inf
    for turn, tilt, roll, bend in itertools.product(
            FIRST_FRAME_TURNS_DEG, FIRST_FRAME_TILTS_DEG, FIRST_FRAME_ROLLS_DEG,
            FIRST_FRAME_FLEXION_DEG):
        rotation = Rotation.from_euler("zyx", [in_plane, turn + roll, tilt + 180.0],
                                       degrees=True)
        candidate = start.copy()
        candidate[ROOT_ROTATION] = rotation.as_rotvec()
        candidate[flexion] = np.radians(bend)
        placed = _positions(model, candidate, camera)
        candidate[:2] -= placed.mean(axis=0)[:2] - placed[root, :2]
        fitted, cost = _fit_frame(model, camera, uv, seen, candidate, None)
        if cost < best_cost:
            best, best_cost = fitted, cost
    return best


def fit_2d(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray, camera: Camera, *,
           hand: str = "right") -> LiftResult:
    """Lift a 2D track by fitting the hand model frame by frame.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64`` pixels, NaN where missing, on ``skeleton``.
    skeleton
        The clip's skeleton; the model moves it.
    bone_lengths
        ``(J,) float64`` clip units, length of the bone ending at each joint.
    camera
        Pinhole or (scaled) orthographic.
    hand
        ``"right"`` or ``"left"``.

    Returns
    -------
    LiftResult
        ``xyz`` in clip units for every joint; no sign confidence (NaN); length
        inconsistency zero (the model keeps every length).
    """
    model, k = _model_lengths(skeleton, bone_lengths, hand)
    points = uv
    seen = finite_points(points)
    fitted = np.flatnonzero(seen.sum(axis=1) >= MIN_POINTS)
    if not fitted.size:
        raise ClipDataError(f"no frame has the {MIN_POINTS} image points a model fit needs")
    params = np.empty((len(points), N_DOF + 1))
    previous = _first_frame(model, camera, points[fitted[0]], seen[fitted[0]])
    for t in range(len(points)):
        if seen[t].sum() >= MIN_POINTS:
            previous, _ = _fit_frame(model, camera, points[t], seen[t], previous, previous)
        params[t] = previous
    xyz = _positions(model, params, camera) / k
    n_frames, n_joints = uv.shape[:2]
    scale = (np.exp(params[:, LOG_SCALE]) * k if camera.model == "orthographic"
             else np.full(n_frames, np.nan))
    inconsistency = np.where(np.isfinite(xyz[..., 0]), 0.0, np.nan)
    return LiftResult(
        xyz=xyz,
        sign_confidence=np.full((n_frames, n_joints), np.nan),
        length_inconsistency=inconsistency,
        scale=scale,
        method=METHOD,
        note="joints without an image point are placed by the fitted model",
    )

