"""Joint angles of a hand, their anatomical limits, and forward kinematics.

A pose is a vector of ``N_ANGLES`` joint angles in radians, in the order of
:data:`ANGLE_NAMES`:

* each long finger (index, middle, ring, little): MCP flexion and abduction, PIP flexion,
  DIP flexion;
* the thumb: CMC flexion and abduction, MCP flexion, IP flexion.

Flexion is positive toward the palm (``+z`` of the hand frame, see
:mod:`handdb.synthetic.hand_model`). Abduction is positive when a finger spreads away from
the middle finger (the middle finger itself: toward the thumb); for the thumb it is palmar
abduction, lifting the thumb off the palm plane. Each joint turns the bone that *leaves*
it: MCP abduction is about the palm normal, and flexion about the bone's lateral axis after
abduction, so a finger's three flexions act in one plane.
"""

from __future__ import annotations

import numpy as np

from handdb.hand.skeletons import FINGERS
from handdb.synthetic.hand_model import HandModel, mirror_sign

THUMB_ANGLES: tuple[str, ...] = (
    "thumb_cmc_flexion", "thumb_cmc_abduction", "thumb_mcp_flexion", "thumb_ip_flexion",
)

#: Names of the joint angles, in the order of a pose vector.
ANGLE_NAMES: tuple[str, ...] = THUMB_ANGLES + tuple(
    f"{finger}_{dof}"
    for finger in FINGERS[1:]
    for dof in ("mcp_flexion", "mcp_abduction", "pip_flexion", "dip_flexion")
)
N_ANGLES = len(ANGLE_NAMES)
ANGLE_INDEX: dict[str, int] = {name: i for i, name in enumerate(ANGLE_NAMES)}

#: Active range of motion, degrees ``(min, max)``. Flexion ranges are the usual clinical
#: values (MCP -20..90, PIP 0..110, DIP 0..90; thumb MCP 0..60, IP -15..80); abduction
#: allows the maximal spread between neighbouring fingers measured in young adults
#: (about 17 deg index-middle, 14 deg middle-ring, 32 deg ring-little).
ANGLE_LIMITS_DEG: dict[str, tuple[float, float]] = {
    "thumb_cmc_flexion": (-15.0, 50.0),
    "thumb_cmc_abduction": (-10.0, 60.0),
    "thumb_mcp_flexion": (0.0, 60.0),
    "thumb_ip_flexion": (-15.0, 80.0),
    **{f"{f}_mcp_flexion": (-20.0, 90.0) for f in FINGERS[1:]},
    **{f"{f}_pip_flexion": (0.0, 110.0) for f in FINGERS[1:]},
    **{f"{f}_dip_flexion": (0.0, 90.0) for f in FINGERS[1:]},
    "index_mcp_abduction": (-10.0, 20.0),
    "middle_mcp_abduction": (-10.0, 10.0),
    "ring_mcp_abduction": (-10.0, 15.0),
    "little_mcp_abduction": (-10.0, 30.0),
}

#: Limits as ``(N_ANGLES, 2) float64`` radians, rows in :data:`ANGLE_NAMES` order.
ANGLE_LIMITS = np.radians(np.array([ANGLE_LIMITS_DEG[name] for name in ANGLE_NAMES]))

#: DIP flexion that accompanies PIP flexion in a natural, unloaded finger.
DIP_PIP_COUPLING = 2.0 / 3.0

#: Sense of rotation about the bone's flexion-side axis that spreads each finger.
SPREAD_SIGN: dict[str, float] = {
    "thumb": -1.0, "index": -1.0, "middle": -1.0, "ring": 1.0, "little": 1.0,
}

#: Rotation taking the hand frame to the camera frame so that the palm faces the camera
#: with the fingers pointing up: hand ``x`` -> camera ``x``, ``y`` -> ``-y``, ``z`` -> ``-z``.
PALM_TO_CAMERA = np.diag([1.0, -1.0, -1.0])

#: The angles that drive the bone ending at a joint: ``{joint: (flexion, abduction)}``.
BONE_ANGLES: dict[str, tuple[str, str | None]] = {
    "thumb_mcp": ("thumb_cmc_flexion", "thumb_cmc_abduction"),
    "thumb_ip": ("thumb_mcp_flexion", None),
    "thumb_tip": ("thumb_ip_flexion", None),
    **{
        joint: dof
        for f in FINGERS[1:]
        for joint, dof in (
            (f"{f}_pip", (f"{f}_mcp_flexion", f"{f}_mcp_abduction")),
            (f"{f}_dip", (f"{f}_pip_flexion", None)),
            (f"{f}_tip", (f"{f}_dip_flexion", None)),
        )
    },
}


def clip_to_limits(angles: np.ndarray) -> np.ndarray:
    """Return ``angles`` ``(..., N_ANGLES)`` radians clipped to :data:`ANGLE_LIMITS`."""
    return np.clip(angles, ANGLE_LIMITS[:, 0], ANGLE_LIMITS[:, 1])


def _rotation_x(theta: np.ndarray) -> np.ndarray:
    """Rotations about ``x`` by ``theta`` ``(T,)`` radians, ``(T, 3, 3)``."""
    c, s = np.cos(theta), np.sin(theta)
    one, zero = np.ones_like(theta), np.zeros_like(theta)
    return np.stack([
        np.stack([one, zero, zero], -1),
        np.stack([zero, c, -s], -1),
        np.stack([zero, s, c], -1),
    ], axis=-2)


def _rotation_z(theta: np.ndarray) -> np.ndarray:
    """Rotations about ``z`` by ``theta`` ``(T,)`` radians, ``(T, 3, 3)``."""
    c, s = np.cos(theta), np.sin(theta)
    one, zero = np.ones_like(theta), np.zeros_like(theta)
    return np.stack([
        np.stack([c, -s, zero], -1),
        np.stack([s, c, zero], -1),
        np.stack([zero, zero, one], -1),
    ], axis=-2)


def _per_frame(value: np.ndarray | None, n_frames: int, default: np.ndarray) -> np.ndarray:
    """Broadcast a constant or per-frame root transform to ``n_frames`` frames."""
    value = default if value is None else np.asarray(value, dtype=np.float64)
    return np.broadcast_to(value, (n_frames, *default.shape))


def local_kinematics(model: HandModel, angles: np.ndarray) -> np.ndarray:
    """Joint positions in the hand's own frame (root at the origin).

    Parameters
    ----------
    model
        The hand.
    angles
        ``(T, N_ANGLES) float64``, radians, in :data:`ANGLE_NAMES` order.

    Returns
    -------
    (T, J, 3) float64
        Positions in ``model.units``; a left hand is mirrored (``x -> -x``).
    """
    angles = np.asarray(angles, dtype=np.float64)
    if angles.ndim != 2 or angles.shape[1] != N_ANGLES:
        raise ValueError(f"angles must have shape (T, {N_ANGLES}), got {angles.shape}")
    skeleton = model.skeleton
    n_frames = angles.shape[0]
    frames = np.empty((n_frames, skeleton.n_joints, 3, 3))
    positions = np.zeros((n_frames, skeleton.n_joints, 3))
    frames[:, skeleton.root] = np.eye(3)
    for joint, parent in enumerate(skeleton.parents):
        if parent < 0:
            continue
        rest = model.bone_frames[parent].T @ model.bone_frames[joint]
        frame = frames[:, parent] @ rest
        flexion, abduction = BONE_ANGLES.get(skeleton.joints[joint], (None, None))
        if abduction is not None:
            spread = SPREAD_SIGN[skeleton.fingers[joint]] * angles[:, ANGLE_INDEX[abduction]]
            frame = frame @ _rotation_z(spread)
        if flexion is not None:
            frame = frame @ _rotation_x(angles[:, ANGLE_INDEX[flexion]])
        frames[:, joint] = frame
        positions[:, joint] = positions[:, parent] + model.bone_lengths[joint] * frame[:, :, 1]
    return positions * mirror_sign(model.hand)


def forward_kinematics(
    model: HandModel,
    angles: np.ndarray,
    root_rotation: np.ndarray | None = None,
    root_translation: np.ndarray | None = None,
) -> np.ndarray:
    """Joint positions in the camera frame for a sequence of poses.

    Parameters
    ----------
    model
        The hand.
    angles
        ``(T, N_ANGLES) float64``, radians, in :data:`ANGLE_NAMES` order.
    root_rotation
        ``(T, 3, 3)`` or ``(3, 3)`` rotation taking the hand's own frame (mirrored for a
        left hand) to the camera frame (x right, y down, z away from the camera). Default:
        :data:`PALM_TO_CAMERA`.
    root_translation
        ``(T, 3)`` or ``(3,)``: camera-frame position of the root joint, ``model.units``.
        Default: the origin.

    Returns
    -------
    (T, J, 3) float64
        Joint positions, ``model.units``, camera frame.
    """
    local = local_kinematics(model, angles)
    n_frames = local.shape[0]
    rotation = _per_frame(root_rotation, n_frames, PALM_TO_CAMERA)
    translation = _per_frame(root_translation, n_frames, np.zeros(3))
    return np.einsum("tij,tkj->tki", rotation, local) + translation[:, None, :]
