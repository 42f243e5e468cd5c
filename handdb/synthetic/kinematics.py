"""Joint angles of synthetic motions, and the hand model posed by them.

A motion's angles are the 27 joint angles of the kinematic model
(:mod:`handdb.hand.model`) in one order for every skeleton, :data:`ANGLE_NAMES`
(``thumb_cmc_abduction``, ..., ``little_dip_flexion``), radians, with the conventions and
active ranges of :mod:`handdb.hand.anatomy`. :func:`model_poses` turns them, with the
hand's orientation and position in the camera frame, into the model's pose vectors.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.hand import anatomy
from handdb.hand.model import N_DOF, ROOT_POSITION, ROOT_ROTATION, HandModel, forward_kinematics
from handdb.hand.skeletons import FINGERS

#: The joints that articulate, per finger, base to tip.
_JOINTS: dict[str, tuple[str, ...]] = {
    "thumb": ("cmc", "mcp", "ip"), **{f: ("mcp", "pip", "dip") for f in FINGERS[1:]},
}

#: Names of the joint angles, in the order of a motion's angle vectors.
ANGLE_NAMES: tuple[str, ...] = tuple(
    f"{finger}_{joint}_{axis}"
    for finger in FINGERS for joint in _JOINTS[finger] for axis in anatomy.JOINT_AXES[joint]
)
N_ANGLES = len(ANGLE_NAMES)
ANGLE_INDEX: dict[str, int] = {name: i for i, name in enumerate(ANGLE_NAMES)}

#: Active ranges as ``(N_ANGLES, 2) float64`` radians, rows in :data:`ANGLE_NAMES` order.
ANGLE_LIMITS = np.array([anatomy.range_of_motion(*name.split("_")) for name in ANGLE_NAMES])

#: Rotation taking the hand frame to the camera frame so that the palm faces the camera
#: with the fingers pointing up: hand ``x`` -> camera ``x``, ``y`` -> ``-y``, ``z`` -> ``-z``.
PALM_TO_CAMERA = np.diag([1.0, -1.0, -1.0])


def clip_to_limits(angles: np.ndarray) -> np.ndarray:
    """Return ``angles`` ``(..., N_ANGLES)`` radians clipped to :data:`ANGLE_LIMITS`."""
    return np.clip(angles, ANGLE_LIMITS[:, 0], ANGLE_LIMITS[:, 1])


def _model_order(model: HandModel) -> np.ndarray:
    """Where each of the model's joint angles is in :data:`ANGLE_NAMES`, ``(27,) int64``."""
    return np.array([ANGLE_INDEX[name.replace(".", "_")] for name in model.dof_names[6:]])


def model_poses(model: HandModel, angles: np.ndarray, root_rotation: np.ndarray | None = None,
                root_translation: np.ndarray | None = None) -> np.ndarray:
    """The model's pose vectors for joint angles and a hand placement.

    Parameters
    ----------
    model
        The hand.
    angles
        ``(T, N_ANGLES) float64``, radians, :data:`ANGLE_NAMES` order.
    root_rotation
        ``(T, 3, 3)`` or ``(3, 3)``: the hand frame to the camera frame, as for a right
        hand (a left hand's is its mirror image). Default :data:`PALM_TO_CAMERA`.
    root_translation
        ``(T, 3)`` or ``(3,)``: camera-frame position of the root joint, ``model.units``.
        Default the origin.

    Returns
    -------
    (T, 33) float64
    """
    angles = np.asarray(angles, dtype=np.float64)
    if angles.ndim != 2 or angles.shape[1] != N_ANGLES:
        raise ValueError(f"angles must have shape (T, {N_ANGLES}), got {angles.shape}")
    n_frames = angles.shape[0]
    rotation = np.array(np.broadcast_to(PALM_TO_CAMERA if root_rotation is None
                                        else root_rotation, (n_frames, 3, 3)))
    translation = np.broadcast_to(np.zeros(3) if root_translation is None
                                  else root_translation, (n_frames, 3))
    poses = np.zeros((n_frames, N_DOF))
    poses[:, ROOT_POSITION] = translation
    poses[:, ROOT_ROTATION] = Rotation.from_matrix(rotation).as_rotvec()
    poses[:, 6:] = angles[:, _model_order(model)]
    return poses


def local_positions(model: HandModel, angles: np.ndarray) -> np.ndarray:
    """Joint positions in the hand's own frame (root at the origin), ``(T, J, 3)``.

    A left hand comes out mirrored (``x -> -x``).
    """
    return forward_kinematics(model, model_poses(model, angles, np.eye(3)))
