"""A marker clip end to end: calibrate the subject, fit key frames, fill the frames between.

This is the system of Zhao, Chai & Xu (SCA 2012) on marker data alone: subject calibration
(§4) when the clip gives no bone lengths, sequential pose fitting of key frames (§5), and
interpolation of the poses between key frames refined to their visible markers (§6,
eq. 12). Markers come in clip units, one per joint of a skeleton preset the hand model
moves (``mediapipe21``, ``dhg22``, ...); fitting runs in millimetres, the unit of the
paper's cut-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from handdb.checks import as_points, check_hand, mm_per_unit
from handdb.clip import ClipSpec, finite_points
from handdb.errors import ClipDataError, ParameterError
from handdb.export.rotations import JointMotion
from handdb.hand.model import (
    MODEL_SKELETON,
    ROOT_ROTATION,
    HandModel,
    build_hand_model,
    forward_kinematics,
    joint_transforms,
)
from handdb.hand.skeletons import Skeleton
from handdb.lengths.bone_lengths import BoneLengths
from handdb.lifting.result import LiftResult
from handdb.markers.calibration import (
    Calibration,
    calibrate,
    calibrate_reachable,
    calibrated_bone_lengths,
)
from handdb.markers.solve import (
    SwarmSettings,
    carry_unconstrained,
    constrained_dofs,
    filter_and_refine,
    initial_pose,
    interpolate_poses,
    refine_poses,
    track,
)
from handdb.store import tables

#: Pose solver used unless asked otherwise: least squares, which reaches the swarm's
#: accuracy in a fraction of its time (``benchmarks/RESULTS-fitting.md``).
DEFAULT_SOLVER = "lsq"

#: Frames from one key frame to the next. The paper's key frames are its Kinect frames
#: (a quarter of its Vicon frames); with markers alone every frame can be a key frame,
#: which follows fast motion best (``benchmarks/RESULTS-fitting.md``); a larger step
#: trades accuracy for speed.
KEY_STEP = 1

#: Name of the method in ``joints_3d.lift_method`` and ``clips.lift_method``.
METHOD_NAME = "marker-fit"

#: Markers a frame needs for a first pose.
MIN_START_MARKERS = 3

#: Joints a clip must mark, and the calibration frames each show, for the model's 33
#: degrees of freedom to be determined (three coordinates per marker).
MIN_JOINT_MARKERS = 11

#: Axis names of the root's orientation rows in ``joint_angles`` (rotation vector).
ROOT_AXES = ("rotvec_x", "rotvec_y", "rotvec_z")


@dataclass(frozen=True)
class MarkerFit:
    """A marker clip fitted with the hand model.

    Attributes
    ----------
    model
        The hand model fitted, lengths in mm.
    poses
        ``(T, 33) float64``: root position (mm), root rotation vector and joint angles (rad).
    joints
        ``(T, J, 3) float64`` joint positions from forward kinematics, clip units.
    residual
        ``(T, J) float64`` distance from each visible marker to its joint, clip units; NaN
        where the marker is missing.
    calibration
        The subject calibration, or ``None`` when the bone lengths were given.
    key_frames
        ``(K,) int64`` frames fitted in sequence; the others were interpolated and refined.
    """

    model: HandModel
    poses: np.ndarray
    joints: np.ndarray
    residual: np.ndarray
    calibration: Calibration | None
    key_frames: np.ndarray


def key_frames(n_frames: int, step: int = KEY_STEP) -> np.ndarray:
    """Every ``step``-th frame and the last one, ``(K,) int64``."""
    if step < 1:
        raise ParameterError(f"key frame step must be at least 1, got {step}")
    return np.unique(np.append(np.arange(0, n_frames, step), n_frames - 1))


def fit_markers(markers: np.ndarray, *, hand: str = "right", units: str = "mm",
                skeleton: str = MODEL_SKELETON,
                bone_lengths: dict[str, float] | None = None, solver: str = DEFAULT_SOLVER,
                key_step: int = KEY_STEP, correspondence: str = "labelled",
                filter_passes: int = 1, settings: SwarmSettings | None = None,
                seed: int = 0, calibration_limit_weight: float | None = None) -> MarkerFit:
    """Fit the 33-DoF hand model to a marker track.

    Parameters
    ----------
    markers
        ``(T, J, 3) float64`` marker positions on the joints of ``skeleton``, clip units,
        NaN where a marker is missing.
    hand
        ``"right"`` or ``"left"``.
    units
        The clip's length unit (a key of :data:`handdb.clip.METERS_PER_UNIT`).
    skeleton
        The skeleton preset of the joint axis.
    bone_lengths
        Child joint -> length in clip units; when given, calibration is skipped and bones
        not named keep the template length.
    solver
        ``"lsq"`` or ``"pso"`` for the key frames and the refinement.
    key_step
        Frames between key frames; 1 fits every frame in sequence.
    correspondence
        Marker correspondence of the swarm's marker term: ``"labelled"`` or ``"nearest"``.
    filter_passes
        Passes of per-frame IK plus filtering over the whole track (0 for none).
    settings
        Particle swarm settings (default: the paper's).
    seed
        Seed of the swarm's random numbers.
    calibration_limit_weight
        Weight of the calibration poses' angles beyond the joint bounds, mm per radian
        (:func:`~handdb.markers.calibration.calibrate`'s ``limit_weight``); ``None``, the
        default, weighs them only when the tracker cannot reach the free calibration
        (:func:`~handdb.markers.calibration.calibrate_reachable`).

    Returns
    -------
    MarkerFit
    """
    scale = mm_per_unit(units)
    template = build_hand_model(check_hand(hand), skeleton=skeleton)
    mm = as_points(markers, template.n_joints, 3, "markers") * scale
    visible = np.asarray(finite_points(mm))
    _check_enough_markers(template.skeleton, visible, calibrating=not bone_lengths)
    if bone_lengths:
        model = build_hand_model(hand, {k: v * scale for k, v in bone_lengths.items()},
                                 skeleton=skeleton)
        calibration = None
    else:
        calibration = (calibrate_reachable(template, mm) if calibration_limit_weight is None
                       else calibrate(template, mm, limit_weight=calibration_limit_weight))
        model = calibration.model
    rich = np.flatnonzero(visible.sum(axis=1) >= MIN_START_MARKERS)
    if not rich.size:
        raise ClipDataError(f"no frame has the {MIN_START_MARKERS} markers a first pose needs")
    start = initial_pose(model, mm[rich[0]], visible[rich[0]])
    rng = np.random.default_rng(seed)
    keys = key_frames(len(mm), key_step)
    key_poses = track(model, mm[keys], solver=solver, start=start,
                      correspondence=correspondence, settings=settings, rng=rng)
    between = np.setdiff1d(np.arange(len(mm)), keys)
    poses = np.empty((len(mm), key_poses.shape[1]))
    poses[keys] = key_poses
    if between.size:
        guesses = interpolate_poses(keys, key_poses, between)
        poses[between] = refine_poses(model, mm[between], guesses, solver=solver,
                                      settings=settings, rng=rng)
    poses = carry_unconstrained(poses, constrained_dofs(model, visible))
    poses = filter_and_refine(model, mm, poses, passes=filter_passes)
    joints = forward_kinematics(model, poses)
    residual = np.where(visible, np.linalg.norm(joints - mm, axis=-1), np.nan)
    return MarkerFit(model=model, poses=poses, joints=joints / scale,
                     residual=residual / scale, calibration=calibration,
                     key_frames=keys)


def _check_enough_markers(skeleton: Skeleton, visible: np.ndarray, *,
                          calibrating: bool) -> None:
    """Refuse a marker track that cannot determine the hand model's pose or shape.

    Raises
    ------
    ClipDataError
        If fewer than :data:`MIN_JOINT_MARKERS` joints are ever marked, or, when the
        subject is to be calibrated, no frame shows that many.
    """
    joints = skeleton.joints
    marked = [joints[j] for j in np.flatnonzero(visible.any(axis=0))]
    advice = ("map more of the clip's markers to joints in the sidecar's joint_map, or "
              "give the clip as 2D tracks")
    if len(marked) < MIN_JOINT_MARKERS:
        raise ClipDataError(
            f"marker fitting needs at least {MIN_JOINT_MARKERS} of the {len(joints)} joints "
            f"marked (the hand model has 33 degrees of freedom); the clip marks "
            f"{len(marked)}: {', '.join(marked) or 'none'}. To fix: {advice}")
    richest = int(visible.sum(axis=1).max())
    if calibrating and richest < MIN_JOINT_MARKERS:
        raise ClipDataError(
            f"subject calibration needs frames showing at least {MIN_JOINT_MARKERS} markers; "
            f"the richest frame shows {richest}. To fix: give the subject's bone_lengths in "
            f"the sidecar, or {advice}")


def fitted_bone_lengths(fit: MarkerFit, spec: ClipSpec) -> BoneLengths:
    """The bone lengths of a marker fit, in the clip's units, with their source.

    Calibrated lengths when the fit calibrated the subject; otherwise the sidecar's
    lengths where it gives them and the model's template for the rest.
    """
    if fit.calibration is not None:
        return calibrated_bone_lengths(fit.calibration, spec.units)
    skeleton = fit.model.skeleton
    lengths = np.full(skeleton.n_joints, np.nan)
    lengths[skeleton.bones[:, 1]] = fit.model.bone_lengths / mm_per_unit(spec.units)
    given = [j in spec.bone_lengths for j in skeleton.joints]
    sources = tuple(None if j == skeleton.root else "given" if g else "proportions"
                    for j, g in enumerate(given))
    details = tuple(None if j == skeleton.root else f"bone_lengths in {spec.path}" if g
                    else "the hand model's template" for j, g in enumerate(given))
    return BoneLengths(skeleton=skeleton, units=spec.units, lengths=lengths, sources=sources,
                       details=details, residuals=np.full(skeleton.n_joints, np.nan),
                       n_frames=np.zeros(skeleton.n_joints, dtype=np.int64),
                       uncertainty=np.full(skeleton.n_joints, np.nan))


def fit_positions(fit: MarkerFit) -> LiftResult:
    """The fitted joints as a :class:`~handdb.lifting.LiftResult` (method ``marker-fit``).

    A fit has no depth signs, scale or length slack of its own: those arrays are NaN.
    """
    n_frames, n_joints = fit.joints.shape[:2]
    unknown = np.full((n_frames, n_joints), np.nan)
    return LiftResult(xyz=fit.joints, sign_confidence=unknown, length_inconsistency=unknown,
                      scale=np.full(n_frames, np.nan), method=METHOD_NAME)


def joint_motion(fit: MarkerFit, units: str = "mm") -> JointMotion:
    """Return the fit's local joint transforms for the USD and BVH exporters (clip units).

    Rotations are the model's own joint rotations (:func:`~handdb.hand.model.joint_transforms`)
    rather than ones inferred from positions; translations are the model's bone offsets in
    each parent's frame (``+Y`` along finger bones), the root's its world position.

    Parameters
    ----------
    fit
        A marker fit.
    units
        The clip's length unit, the unit of the translations.
    """
    rotations, translations = joint_transforms(fit.model, fit.poses)
    translations = translations / mm_per_unit(units)
    flips = np.sum(rotations[1:] * rotations[:-1], axis=-1) < 0
    signs = np.concatenate([np.ones((1,) + flips.shape[1:]),
                            np.cumprod(np.where(flips, -1.0, 1.0), axis=0)])
    return JointMotion(rotations=rotations * signs[..., None], translations=translations)


def joint_angles_table(clip_id: str, model: HandModel, poses: np.ndarray) -> pa.Table:
    """Table ``joint_angles``: every joint angle of every frame, degrees.

    Rows name the joint and the axis (``abduction``, ``flexion``, ``twist``); the wrist's
    orientation in the world is given as a rotation vector (``rotvec_x`` .. ``rotvec_z``).

    Parameters
    ----------
    clip_id
        The clip.
    model
        The hand model the poses belong to.
    poses
        ``(T, 33)`` poses.
    """
    root = model.skeleton.joints[model.skeleton.root]
    joint = [root] * len(ROOT_AXES) + [name.split(".")[0] for name in model.dof_names[6:]]
    axis = list(ROOT_AXES) + [name.split(".")[1] for name in model.dof_names[6:]]
    angles = np.degrees(np.concatenate([poses[:, ROOT_ROTATION], poses[:, 6:]], axis=1))
    n_frames, n_angles = angles.shape
    return tables.from_columns("joint_angles", {
        "clip_id": clip_id,
        "frame": np.repeat(np.arange(n_frames, dtype=np.int32), n_angles),
        "joint": np.tile(np.array(joint), n_frames),
        "axis": np.tile(np.array(axis), n_frames),
        "angle_deg": angles.ravel(),
    })

