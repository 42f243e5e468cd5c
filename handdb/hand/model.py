"""The 33-degree-of-freedom kinematic hand model of Zhao, Chai & Xu (SCA 2012, Figure 5).

The model lives on the ``mediapipe21`` skeleton. A pose ``q`` holds 33 numbers:

* ``q[0:3]`` root (wrist) position, length units of the bone lengths;
* ``q[3:6]`` root orientation as a rotation vector, radians;
* 27 joint angles, radians, joint by joint in skeleton order: the thumb's
  trapeziometacarpal joint (``thumb_cmc``) and its MCP joint have three degrees of freedom
  each (abduction, flexion, twist), its IP joint one (flexion); each other finger has a
  three-degree MCP joint and one-degree PIP and DIP joints.

Each joint carries a frame. In the rest pose (every angle zero) the hand frame has x
towards the thumb side, y from the wrist to the fingers and z out of the palm, for a right
hand; a left hand is its mirror image in x. A finger joint's frame has y along the bone it
moves; flexion turns about its x axis (positive bends the finger towards the palm),
abduction about its z axis (positive towards the little finger), twist about its y axis.
A three-degree joint applies abduction, then flexion, then twist (intrinsic z-x-y).
The palm bones (wrist to ``thumb_cmc`` and to each MCP joint) are rigid with the root.

Bone lengths are parameters (``(..., 20)``, in ``Skeleton.bone_names`` order), so one forward
kinematics call evaluates many frames, particles or candidate skeletons at once.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.errors import SkeletonError
from handdb.hand.skeletons import Skeleton, load_skeleton

#: Skeleton preset the model is defined on.
MODEL_SKELETON = "mediapipe21"

#: Number of pose parameters: 6 for the root, 27 joint angles.
N_DOF = 33

#: Pose parameters of the root: position (3) then rotation vector (3).
ROOT_POSITION = slice(0, 3)
ROOT_ROTATION = slice(3, 6)

#: Axis names of a joint's angles, in the order a three-degree joint applies them, and the
#: column of each in a joint's ``(abduction, flexion, twist)`` angle triple.
AXES: tuple[str, ...] = ("abduction", "flexion", "twist")

#: Degrees of freedom of each role that articulates.
ROLE_DOF: dict[str, tuple[str, ...]] = {
    "cmc": AXES,
    "mcp": AXES,
    "pip": ("flexion",),
    "dip": ("flexion",),
    "ip": ("flexion",),
}

#: Joint limits in degrees, (lower, upper), by (finger kind, role, axis); generous ranges of
#: active motion, wide enough for tracker noise.
JOINT_LIMITS_DEG: dict[tuple[str, str, str], tuple[float, float]] = {
    ("thumb", "cmc", "abduction"): (-60.0, 60.0),
    ("thumb", "cmc", "flexion"): (-60.0, 70.0),
    ("thumb", "cmc", "twist"): (-60.0, 60.0),
    ("thumb", "mcp", "abduction"): (-35.0, 35.0),
    ("thumb", "mcp", "flexion"): (-35.0, 95.0),
    ("thumb", "mcp", "twist"): (-35.0, 35.0),
    ("thumb", "ip", "flexion"): (-35.0, 100.0),
    ("finger", "mcp", "abduction"): (-35.0, 35.0),
    ("finger", "mcp", "flexion"): (-45.0, 105.0),
    ("finger", "mcp", "twist"): (-35.0, 35.0),
    ("finger", "pip", "flexion"): (-15.0, 125.0),
    ("finger", "dip", "flexion"): (-25.0, 105.0),
}

#: Rest-pose position of each palm joint relative to the wrist, right hand, millimetres, in
#: the hand frame (x thumb side, y distal, z palmar): an average adult hand.
PALM_TEMPLATE_MM: dict[str, tuple[float, float, float]] = {
    "thumb_cmc": (22.0, 28.0, 10.0),
    "index_mcp": (24.0, 84.0, 0.0),
    "middle_mcp": (4.0, 86.0, 0.0),
    "ring_mcp": (-14.0, 80.0, 0.0),
    "little_mcp": (-30.0, 72.0, 0.0),
}

#: Rest-pose length of each finger bone of the average adult hand, millimetres.
FINGER_TEMPLATE_MM: dict[str, float] = {
    "thumb_mcp": 42.0, "thumb_ip": 32.0, "thumb_tip": 28.0,
    "index_pip": 40.0, "index_dip": 23.0, "index_tip": 20.0,
    "middle_pip": 44.0, "middle_dip": 27.0, "middle_tip": 21.0,
    "ring_pip": 41.0, "ring_dip": 26.0, "ring_tip": 21.0,
    "little_pip": 32.0, "little_dip": 19.0, "little_tip": 19.0,
}

#: Rest direction of the thumb metacarpal in the hand frame (towards the thumb side,
#: distally and slightly palmar), and the roll of the thumb's frame about it, degrees,
#: which turns its flexion across the palm.
THUMB_REST_DIRECTION = (0.6, 0.75, 0.28)
THUMB_ROLL_DEG = -60.0

#: Reflection that turns the right-hand model into a left hand.
MIRROR_X = np.diag([-1.0, 1.0, 1.0])


@dataclass(frozen=True)
class HandModel:
    """A kinematic hand: topology, rest geometry, degrees of freedom and joint limits.

    Attributes
    ----------
    skeleton
        The ``mediapipe21`` skeleton.
    hand
        ``"right"`` or ``"left"``.
    bone_lengths
        ``(B,) float64``, one per bone in ``skeleton.bone_names`` order, length units.
    rest_directions
        ``(J, 3) float64`` unit vectors: each bone's direction in its parent joint's frame
        in the rest pose (right-hand coordinates; the root's row is zero).
    alignments
        ``(J, 3, 3) float64``: the rest rotation of each joint's frame in its parent's frame.
    dof_joint, dof_axis
        ``(27,) int64``: the joint and the axis (index into :data:`AXES`) of each joint angle.
    lower, upper
        ``(33,) float64`` joint limits of the pose vector; unbounded for the root.
    """

    skeleton: Skeleton
    hand: str
    bone_lengths: np.ndarray
    rest_directions: np.ndarray
    alignments: np.ndarray
    dof_joint: np.ndarray
    dof_axis: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    @property
    def n_joints(self) -> int:
        """Number of joints ``J``."""
        return self.skeleton.n_joints

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Name of every pose parameter, ``(33,)``: ``"root.x"``, ..., ``"index_mcp.flexion"``."""
        root = ("root.x", "root.y", "root.z", "root.rx", "root.ry", "root.rz")
        joints = tuple(f"{self.skeleton.joints[j]}.{AXES[a]}"
                       for j, a in zip(self.dof_joint, self.dof_axis, strict=True))
        return root + joints

    @property
    def palm_joints(self) -> np.ndarray:
        """Indices of the joints rigid with the root (its children), ``(5,) int64``."""
        return self.skeleton.children(self.skeleton.root)

    def with_geometry(self, bone_lengths: np.ndarray,
                      rest_directions: np.ndarray | None = None) -> HandModel:
        """Return a copy with other bone lengths (and palm shape), leaving this model as it is."""
        lengths = np.asarray(bone_lengths, dtype=np.float64)
        if lengths.shape != self.bone_lengths.shape or not np.all(lengths > 0):
            raise SkeletonError(f"bone lengths must be {self.bone_lengths.shape} and positive")
        directions = self.rest_directions if rest_directions is None else _unit(rest_directions)
        return replace(self, bone_lengths=lengths, rest_directions=directions)

    def rest_pose(self) -> np.ndarray:
        """Pose vector of the rest pose at the origin, ``(33,) float64``."""
        return np.zeros(N_DOF)


def _unit(vectors: np.ndarray) -> np.ndarray:
    vectors = np.asarray(vectors, dtype=np.float64)
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, norms, out=np.zeros_like(vectors), where=norms > 0)


def _align_y(direction: np.ndarray, roll_deg: float = 0.0) -> np.ndarray:
    """Rotation whose y column is ``direction``, keeping x in the hand's x-y plane, then rolled."""
    y = _unit(direction)
    x = _unit(np.cross(y, (0.0, 0.0, 1.0)))
    z = np.cross(x, y)
    basis = np.stack([x, y, z], axis=1)
    return basis @ Rotation.from_euler("y", roll_deg, degrees=True).as_matrix()


def build_hand_model(hand: str = "right", bone_lengths: dict[str, float] | None = None,
                     units_per_mm: float = 1.0) -> HandModel:
    """Build the hand model with the average adult geometry, or the bone lengths given.

    Parameters
    ----------
    hand
        ``"right"`` or ``"left"``.
    bone_lengths
        Child joint -> length in the model's units; bones not named keep the template
        length (scaled by ``units_per_mm``).
    units_per_mm
        Model length units per millimetre (1 for mm, 0.001 for metres).

    Returns
    -------
    HandModel
    """
    if hand not in ("right", "left"):
        raise SkeletonError(f"hand must be 'right' or 'left', got {hand!r}")
    skeleton = load_skeleton(MODEL_SKELETON)
    n = skeleton.n_joints
    directions = np.zeros((n, 3))
    alignments = np.tile(np.eye(3), (n, 1, 1))
    template = {name: float(np.linalg.norm(offset)) for name, offset in PALM_TEMPLATE_MM.items()}
    template.update(FINGER_TEMPLATE_MM)
    for j, name in enumerate(skeleton.joints):
        if name in PALM_TEMPLATE_MM:
            offset = np.array(PALM_TEMPLATE_MM[name])
            directions[j] = offset / np.linalg.norm(offset)
            if skeleton.fingers[j] == "thumb":
                alignments[j] = _align_y(np.array(THUMB_REST_DIRECTION), THUMB_ROLL_DEG)
            else:
                alignments[j] = _align_y(offset * (1.0, 1.0, 0.0))
        elif skeleton.parents[j] >= 0:
            directions[j] = (0.0, 1.0, 0.0)

    given = bone_lengths or {}
    unknown = sorted(set(given) - set(skeleton.bone_names))
    if unknown:
        raise SkeletonError(f"not bones of '{skeleton.name}': {', '.join(unknown)}")
    lengths = np.array([given.get(b, template[b] * units_per_mm) for b in skeleton.bone_names])

    dof_joint, dof_axis, lower, upper = [], [], [], []
    for j, role in enumerate(skeleton.roles):
        kind = "thumb" if skeleton.fingers[j] == "thumb" else "finger"
        for axis in ROLE_DOF.get(role, ()):
            lo, hi = JOINT_LIMITS_DEG[(kind, role, axis)]
            dof_joint.append(j)
            dof_axis.append(AXES.index(axis))
            lower.append(np.radians(lo))
            upper.append(np.radians(hi))
    if len(dof_joint) + 6 != N_DOF:
        raise SkeletonError(f"'{skeleton.name}' does not give the model's {N_DOF} DoF")
    return HandModel(
        skeleton=skeleton,
        hand=hand,
        bone_lengths=np.asarray(lengths, dtype=np.float64),
        rest_directions=directions,
        alignments=alignments,
        dof_joint=np.array(dof_joint, dtype=np.int64),
        dof_axis=np.array(dof_axis, dtype=np.int64),
        lower=np.concatenate([np.full(6, -np.inf), lower]),
        upper=np.concatenate([np.full(6, np.inf), upper]),
    )


def clip_to_limits(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Return ``pose`` (``(..., 33)``) with every joint angle inside the model's limits."""
    return np.clip(pose, model.lower, model.upper)


def joint_euler(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Spread the joint angles of ``pose`` over joints, ``(..., 33) -> (..., J, 3)`` radians.

    The last axis is ``(abduction, flexion, twist)``; angles a joint lacks are zero.
    """
    pose = np.asarray(pose, dtype=np.float64)
    euler = np.zeros(pose.shape[:-1] + (model.n_joints, 3))
    euler[..., model.dof_joint, model.dof_axis] = pose[..., 6:]
    return euler


def euler_matrices(euler: np.ndarray) -> np.ndarray:
    """Rotation matrices of intrinsic z-x-y Euler angles, ``(..., 3) -> (..., 3, 3)``.

    ``euler[..., 0]`` turns about z (abduction), then ``[..., 1]`` about the new x
    (flexion), then ``[..., 2]`` about the new y (twist), radians.
    """
    cos, sin = np.cos(euler), np.sin(euler)
    ca, cb, cc = cos[..., 0], cos[..., 1], cos[..., 2]
    sa, sb, sc = sin[..., 0], sin[..., 1], sin[..., 2]
    zx = np.stack([
        np.stack([ca, -sa * cb, sa * sb], axis=-1),
        np.stack([sa, ca * cb, -ca * sb], axis=-1),
        np.stack([np.zeros_like(sb), sb, cb], axis=-1),
    ], axis=-2)
    first = zx[..., 0] * cc[..., None] - zx[..., 2] * sc[..., None]
    third = zx[..., 0] * sc[..., None] + zx[..., 2] * cc[..., None]
    return np.stack([first, zx[..., 1], third], axis=-1)


def rotvec_matrices(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrices of rotation vectors (Rodrigues), ``(..., 3) -> (..., 3, 3)``, radians."""
    theta = np.linalg.norm(rotvec, axis=-1)
    sin_term = np.sinc(theta / np.pi)
    cos_term = 0.5 * np.sinc(theta / (2.0 * np.pi)) ** 2
    x, y, z = rotvec[..., 0], rotvec[..., 1], rotvec[..., 2]
    zero = np.zeros_like(x)
    cross = np.stack([
        np.stack([zero, -z, y], axis=-1),
        np.stack([z, zero, -x], axis=-1),
        np.stack([-y, x, zero], axis=-1),
    ], axis=-2)
    return (np.eye(3) + sin_term[..., None, None] * cross
            + cos_term[..., None, None] * (cross @ cross))


def local_rotations(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Rotation of each joint's frame in its parent's frame, ``(..., 33) -> (..., J, 3, 3)``.

    The root's entry is its orientation in the world. For a left hand the matrices are
    those of the right-hand model conjugated by the x mirror, so they stay proper rotations.
    """
    pose = np.asarray(pose, dtype=np.float64)
    euler = joint_euler(model, pose)
    local = model.alignments @ euler_matrices(euler)
    local[..., model.skeleton.root, :, :] = rotvec_matrices(pose[..., ROOT_ROTATION])
    if model.hand == "left":
        local = MIRROR_X @ local @ MIRROR_X
    return local


def rest_offsets(model: HandModel, bone_lengths: np.ndarray | None = None,
                 rest_directions: np.ndarray | None = None) -> np.ndarray:
    """Each joint's offset from its parent in the parent's frame, ``(..., J, 3)``.

    ``bone_lengths`` ``(..., B)`` and ``rest_directions`` ``(..., J, 3)`` default to the
    model's. The root's offset is zero.
    """
    lengths = model.bone_lengths if bone_lengths is None else np.asarray(bone_lengths)
    directions = model.rest_directions if rest_directions is None else rest_directions
    per_joint = np.zeros(lengths.shape[:-1] + (model.n_joints,))
    per_joint[..., model.skeleton.bones[:, 1]] = lengths
    offsets = per_joint[..., None] * directions
    return offsets @ MIRROR_X if model.hand == "left" else offsets


def forward_kinematics(model: HandModel, pose: np.ndarray,
                       bone_lengths: np.ndarray | None = None,
                       rest_directions: np.ndarray | None = None,
                       *, with_rotations: bool = False):
    """Joint positions of poses, vectorised over any leading axes (frames, particles).

    Parameters
    ----------
    model
        The hand model.
    pose
        ``(..., 33) float64``: root position (length units), root rotation vector and joint
        angles (radians).
    bone_lengths
        ``(..., B) float64`` broadcastable against ``pose``'s leading axes; default the
        model's.
    rest_directions
        ``(..., J, 3)`` bone directions (see :class:`HandModel`); default the model's.
    with_rotations
        Also return each joint's world rotation.

    Returns
    -------
    positions : numpy.ndarray
        ``(..., J, 3) float64`` in the units of the bone lengths.
    rotations : numpy.ndarray
        ``(..., J, 3, 3)`` world rotation of each joint's frame; only if ``with_rotations``.
    """
    pose = np.asarray(pose, dtype=np.float64)
    local = local_rotations(model, pose)
    offsets = rest_offsets(model, bone_lengths, rest_directions)
    batch = np.broadcast_shapes(pose.shape[:-1], offsets.shape[:-2])
    local = np.broadcast_to(local, batch + local.shape[-3:])
    offsets = np.broadcast_to(offsets, batch + offsets.shape[-2:])
    skeleton = model.skeleton
    depth = skeleton.depth()
    positions = np.empty(batch + (model.n_joints, 3))
    rotations = np.empty(batch + (model.n_joints, 3, 3))
    root = skeleton.root
    positions[..., root, :] = pose[..., ROOT_POSITION]
    rotations[..., root, :, :] = local[..., root, :, :]
    for level in range(1, int(depth.max()) + 1):
        joints = np.flatnonzero(depth == level)
        parents = skeleton.parents[joints]
        parent_rot = rotations[..., parents, :, :]
        moved = (parent_rot @ offsets[..., joints, :, None])[..., 0]
        positions[..., joints, :] = positions[..., parents, :] + moved
        rotations[..., joints, :, :] = parent_rot @ local[..., joints, :, :]
    return (positions, rotations) if with_rotations else positions


def local_quaternions(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Per-joint local rotations as unit quaternions ``(w, x, y, z)``, ``(..., 33) -> (..., J, 4)``.

    Each joint's rotation is relative to its parent joint's frame (the root's to the
    world), with :func:`rest_offsets` as the local translations, the form UsdSkel and BVH
    exporters take.
    """
    local = local_rotations(model, pose)
    xyzw = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat()
    return xyzw[:, [3, 0, 1, 2]].reshape(local.shape[:-2] + (4,))

