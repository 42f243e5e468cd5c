"""The kinematic hand: a hand shape that moves, with 33 degrees of freedom.

The model of Zhao, Chai & Xu (SCA 2012, Figure 5), on any skeleton preset. A pose ``q``
holds 33 numbers:

* ``q[0:3]`` root position, length units of the bone lengths;
* ``q[3:6]`` root orientation as a rotation vector, radians (hand frame to world);
* 27 joint angles, radians: the thumb's carpometacarpal and MCP joints have three axes
  each (abduction, flexion, twist), its IP joint one (flexion); each long finger a
  three-axis MCP joint and one-axis PIP and DIP joints (:data:`handdb.hand.anatomy.
  JOINT_AXES`), in skeleton order.

A joint's angles turn the bone that leaves it (:data:`~handdb.hand.anatomy.MOVING_JOINT`):
each such bone has a rest frame (``x`` lateral, ``y`` along the bone, ``z`` its flexion
side, from the :class:`~handdb.hand.shape.HandShape`) in which abduction turns about ``z``,
then flexion about the new ``x``, then twist about the new ``y`` (intrinsic z-x-y). Bones
no joint moves (the palm's: wrist to knuckles, thumb base, palm centre, palm fold) are
rigid with the root. The angles' conventions and ranges are :mod:`handdb.hand.anatomy`'s;
the model's bounds widen those ranges by :data:`LIMIT_MARGIN_DEG`. A left hand is the
mirror image of the right (``x -> -x``) and its poses mean the same motion.

Bone lengths and the palm's directions are parameters (``(..., B)`` and ``(..., J, 3)``),
so one :func:`forward_kinematics` call evaluates many frames, particles or candidate
hands at once.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.checks import check_hand
from handdb.errors import SkeletonError
from handdb.hand import anatomy
from handdb.hand.anatomy import AXES, JOINT_AXES, MOVING_JOINT
from handdb.hand.shape import HandShape, mean_shape
from handdb.hand.skeletons import Skeleton, load_skeleton

#: Skeleton the model is built on unless told otherwise (the marker set of Zhao et al.).
MODEL_SKELETON = "mediapipe21"

#: Number of pose parameters: 6 for the root, 27 joint angles.
N_DOF = 33

#: Pose parameters of the root: position (3) then rotation vector (3).
ROOT_POSITION = slice(0, 3)
ROOT_ROTATION = slice(3, 6)

#: How far the model's joint bounds reach beyond the active ranges of motion, degrees:
#: what tracker noise and marker offsets from the joint centres add to a real hand's range.
LIMIT_MARGIN_DEG = 20.0

#: Reflection that turns the right-hand model into a left hand.
MIRROR_X = np.diag([-1.0, 1.0, 1.0])



@dataclass(frozen=True)
class HandModel:
    """A kinematic hand: topology, rest geometry, degrees of freedom and joint bounds.

    Attributes
    ----------
    skeleton
        The skeleton the model moves.
    hand
        ``"right"`` or ``"left"``.
    bone_lengths
        ``(B,) float64``, one per bone in ``skeleton.bone_names`` order, length units.
    rest_directions
        ``(J, 3) float64`` unit vectors: each rigid (palm) bone's direction in the hand
        frame, right-hand coordinates; zero for moving bones and the root.
    alignments
        ``(J, 3, 3) float64``: the rest frame of each moving bone in its parent's frame
        (the hand frame for a bone leaving the palm); the identity elsewhere.
    moving
        ``(J,) bool``: the bone ending at the joint is moved by a joint's angles.
    dof_bone, dof_axis
        ``(27,) int64``: the bone (its child joint) each joint angle moves, and the axis
        (index into :data:`~handdb.hand.anatomy.AXES`).
    dof_names
        ``(33,)`` names: ``"root.x"``, ..., ``"index_mcp.flexion"`` (the moving joint).
    lower, upper
        ``(33,) float64`` bounds of the pose vector; unbounded for the root.
    dof_sign
        ``(27,) float64``: ``-1`` where a positive anatomical angle turns the bone the
        negative way about its axis (abduction away from the middle finger on the radial
        side), else ``1``.
    units
        Length unit of ``bone_lengths``.
    """

    skeleton: Skeleton
    hand: str
    bone_lengths: np.ndarray
    rest_directions: np.ndarray
    alignments: np.ndarray
    moving: np.ndarray
    dof_bone: np.ndarray
    dof_axis: np.ndarray
    dof_names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    dof_sign: np.ndarray
    units: str = "mm"

    @property
    def n_joints(self) -> int:
        """Number of joints ``J``."""
        return self.skeleton.n_joints

    @property
    def palm_joints(self) -> np.ndarray:
        """Joints at the end of rigid (palm) bones, ``(P,) int64``."""
        return np.flatnonzero(~self.moving & (self.skeleton.parents >= 0))

    def with_geometry(self, bone_lengths: np.ndarray,
                      rest_directions: np.ndarray | None = None) -> HandModel:
        """A copy with other bone lengths (and palm directions), this model left as it is."""
        lengths = np.asarray(bone_lengths, dtype=np.float64)
        if lengths.shape != self.bone_lengths.shape or not np.all(lengths > 0):
            raise SkeletonError(f"bone lengths must be {self.bone_lengths.shape} and positive")
        directions = (self.rest_directions if rest_directions is None
                      else _unit(rest_directions) * ~self.moving[:, None])
        return replace(self, bone_lengths=lengths, rest_directions=directions)

    def rest_pose(self) -> np.ndarray:
        """Pose vector of the rest pose at the origin, ``(33,) float64``."""
        return np.zeros(N_DOF)

    def bone_length_array(self) -> np.ndarray:
        """Bone lengths by child joint, ``(J,) float64``, NaN at the root."""
        lengths = np.full(self.n_joints, np.nan)
        lengths[self.skeleton.bones[:, 1]] = self.bone_lengths
        return lengths


def _unit(vectors: np.ndarray) -> np.ndarray:
    vectors = np.asarray(vectors, dtype=np.float64)
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, norms, out=np.zeros_like(vectors), where=norms > 0)


def _frame(along: np.ndarray, side: np.ndarray) -> np.ndarray:
    """Rotation with ``y`` along ``along`` and ``z`` towards ``side``, ``(3, 3)``."""
    y = _unit(along)
    z = _unit(side - side @ y * y)
    return np.stack([np.cross(y, z), y, z], axis=1)


def moving_joint(skeleton: Skeleton, bone: int) -> str | None:
    """Role of the joint whose angles move the bone ending at ``bone``; ``None`` if rigid."""
    return MOVING_JOINT.get((skeleton.fingers[bone], skeleton.roles[bone]))


def build_hand_model(hand: str = "right", bone_lengths: dict[str, float] | None = None, *,
                     skeleton: str | Skeleton = MODEL_SKELETON,
                     shape: HandShape | None = None, units_per_mm: float = 1.0,
                     limit_margin_deg: float = LIMIT_MARGIN_DEG) -> HandModel:
    """Build the kinematic model of a hand.

    Parameters
    ----------
    hand
        ``"right"`` or ``"left"``.
    bone_lengths
        Child joint -> length in the model's units; bones not named keep the shape's.
    skeleton
        The skeleton (or its preset name) the model moves.
    shape
        The hand at rest, in the model's units (default: the average adult hand,
        :func:`~handdb.hand.shape.mean_shape`, scaled by ``units_per_mm``).
    units_per_mm
        Model length units per millimetre, for the default shape.
    limit_margin_deg
        How far the bounds reach beyond the active ranges of motion.

    Raises
    ------
    ParameterError
        If ``hand`` is not a hand.
    SkeletonError
        If a named bone is not one of the skeleton's, or the skeleton does not give the
        model its 33 degrees of freedom.
    """
    check_hand(hand)
    skel = load_skeleton(skeleton) if isinstance(skeleton, str) else skeleton
    shape = shape if shape is not None else mean_shape().scaled(units_per_mm)
    given = bone_lengths or {}
    unknown = sorted(set(given) - set(skel.bone_names))
    if unknown:
        raise SkeletonError(f"not bones of '{skel.name}': {', '.join(unknown)}")
    lengths = np.full(skel.n_joints, np.nan)
    for name, length in given.items():
        lengths[skel.index(name)] = length
    if given:
        shape = shape.with_bone_lengths(skel, lengths)
    lengths = np.where(np.isfinite(lengths), lengths, shape.bone_lengths(skel))

    points = shape.positions(skel)
    n = skel.n_joints
    rest_frames = np.tile(np.eye(3), (n, 1, 1))
    directions = np.zeros((n, 3))
    alignments = np.tile(np.eye(3), (n, 1, 1))
    moving = np.zeros(n, dtype=bool)
    dof_bone, dof_axis, names, lower, upper, signs = [], [], [], [], [], []
    margin = np.radians(limit_margin_deg)
    for parent, child in skel.bones:
        along = points[child] - points[parent]
        joint = moving_joint(skel, child)
        if joint is None:
            directions[child] = _unit(along)
            continue
        finger = skel.fingers[child]
        moving[child] = True
        rest_frames[child] = _frame(along, shape.flexion_side(finger))
        alignments[child] = rest_frames[parent].T @ rest_frames[child]
        for axis in JOINT_AXES[joint]:
            lo, hi = anatomy.range_of_motion(finger, joint, axis)
            dof_bone.append(child)
            dof_axis.append(AXES.index(axis))
            names.append(f"{finger}_{joint}.{axis}")
            lower.append(lo - margin)
            upper.append(hi + margin)
            signs.append(anatomy.ABDUCTION_SIGN[finger] if axis == "abduction" else 1.0)
    if len(dof_bone) + 6 != N_DOF:
        raise SkeletonError(f"'{skel.name}' does not give the model's {N_DOF} degrees of "
                            f"freedom (it gives {len(dof_bone) + 6})")
    return HandModel(
        skeleton=skel,
        hand=hand,
        bone_lengths=lengths[skel.bones[:, 1]],
        rest_directions=directions,
        alignments=alignments,
        moving=moving,
        dof_bone=np.array(dof_bone, dtype=np.int64),
        dof_axis=np.array(dof_axis, dtype=np.int64),
        dof_names=("root.x", "root.y", "root.z", "root.rx", "root.ry", "root.rz", *names),
        lower=np.concatenate([np.full(6, -np.inf), lower]),
        upper=np.concatenate([np.full(6, np.inf), upper]),
        dof_sign=np.array(signs),
        units=shape.units,
    )


def clip_to_limits(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Return ``pose`` (``(..., 33)``) with every joint angle inside the model's bounds."""
    return np.clip(pose, model.lower, model.upper)


def joint_euler(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """Spread the joint angles of ``pose`` over bones, ``(..., 33) -> (..., J, 3)`` radians.

    The last axis is ``(abduction, flexion, twist)`` of the joint moving each bone, turns
    about the bone's rest axes (abduction signed by :attr:`HandModel.dof_sign`); angles a
    bone lacks are zero.
    """
    pose = np.asarray(pose, dtype=np.float64)
    euler = np.zeros(pose.shape[:-1] + (model.n_joints, 3))
    euler[..., model.dof_bone, model.dof_axis] = pose[..., 6:] * model.dof_sign
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


def _right_hand_pose(model: HandModel, pose: np.ndarray) -> np.ndarray:
    """The right-hand pose whose mirror image is ``pose`` of a left-hand model.

    The mirror takes the root's position to ``(-x, y, z)`` and its orientation ``R`` to
    ``M R M``; the joint angles mean the same motion of either hand.
    """
    if model.hand == "right":
        return pose
    mirrored = pose.copy()
    mirrored[..., 0] = -pose[..., 0]
    return mirrored


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
        ``(..., J, 3)`` directions of the rigid bones (see :class:`HandModel`); default the
        model's.
    with_rotations
        Also return each bone's world frame.

    Returns
    -------
    positions : numpy.ndarray
        ``(..., J, 3) float64`` in the units of the bone lengths.
    rotations : numpy.ndarray
        ``(..., J, 3, 3)`` world frame of the bone ending at each joint (the root's: the
        hand's orientation; a rigid bone's: its parent's); only if ``with_rotations``.
    """
    pose = _right_hand_pose(model, np.asarray(pose, dtype=np.float64))
    lengths = model.bone_lengths if bone_lengths is None else np.asarray(bone_lengths)
    directions = model.rest_directions if rest_directions is None else rest_directions
    per_joint = np.zeros(lengths.shape[:-1] + (model.n_joints,))
    per_joint[..., model.skeleton.bones[:, 1]] = lengths
    batch = np.broadcast_shapes(pose.shape[:-1], per_joint.shape[:-1],
                                np.shape(directions)[:-2])
    per_joint = np.broadcast_to(per_joint, batch + (model.n_joints,))
    directions = np.broadcast_to(directions, batch + (model.n_joints, 3))
    turns = model.alignments @ euler_matrices(joint_euler(model, pose))
    skeleton = model.skeleton
    root = skeleton.root
    positions = np.empty(batch + (model.n_joints, 3))
    frames = np.empty(batch + (model.n_joints, 3, 3))
    positions[..., root, :] = pose[..., ROOT_POSITION]
    frames[..., root, :, :] = rotvec_matrices(pose[..., ROOT_ROTATION])
    depth = skeleton.depth()
    for level in range(1, int(depth.max()) + 1):
        at_level = np.flatnonzero(depth == level)
        for joints, moved in ((at_level[model.moving[at_level]], True),
                              (at_level[~model.moving[at_level]], False)):
            if not joints.size:
                continue
            parents = skeleton.parents[joints]
            parent_frames = frames[..., parents, :, :]
            if moved:
                frames[..., joints, :, :] = parent_frames @ turns[..., joints, :, :]
                offsets = frames[..., joints, :, :][..., 1] * per_joint[..., joints, None]
            else:
                frames[..., joints, :, :] = parent_frames
                local = directions[..., joints, :, None]
                offsets = (parent_frames @ local)[..., 0] * per_joint[..., joints, None]
            positions[..., joints, :] = positions[..., parents, :] + offsets
    if model.hand == "left":
        positions = positions @ MIRROR_X
        frames = MIRROR_X @ frames @ MIRROR_X
    return (positions, frames) if with_rotations else positions


def joint_frames(model: HandModel, bone_frames: np.ndarray) -> np.ndarray:
    """Each joint's frame for animation: ``+Y`` along the bone to its child.

    A joint with one child that a joint's angles move takes that child bone's frame; a
    fingertip keeps its bone's frame (its parent's orientation); the root and the other
    joints with several children (or rigid ones) keep their own.

    Parameters
    ----------
    model
        The hand model.
    bone_frames
        ``(..., J, 3, 3)`` world frames from :func:`forward_kinematics`.
    """
    skeleton = model.skeleton
    frames = bone_frames.copy()
    for joint in range(model.n_joints):
        children = skeleton.children(joint)
        if len(children) == 1 and model.moving[children[0]]:
            frames[..., joint, :, :] = bone_frames[..., children[0], :, :]
    return frames


def joint_transforms(model: HandModel, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local joint transforms of poses, the form the UsdSkel and BVH exporters take.

    Returns
    -------
    rotations : numpy.ndarray
        ``(..., J, 4)`` unit quaternions ``(w, x, y, z)``: each joint's frame
        (:func:`joint_frames`) in its parent's (the root's in the world).
    translations : numpy.ndarray
        ``(..., J, 3)``: each joint's offset from its parent in the parent's frame (the
        root's: its world position), in the model's length units.
    """
    positions, bone_frames = forward_kinematics(model, pose, with_rotations=True)
    frames = joint_frames(model, bone_frames)
    parents = model.skeleton.parents.copy()
    root = model.skeleton.root
    parents[root] = root
    parent_frames = frames[..., parents, :, :]
    local = np.swapaxes(parent_frames, -1, -2) @ frames
    local[..., root, :, :] = frames[..., root, :, :]
    offsets = positions - positions[..., parents, :]
    translations = (np.swapaxes(parent_frames, -1, -2) @ offsets[..., None])[..., 0]
    translations[..., root, :] = positions[..., root, :]
    xyzw = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat()
    rotations = xyzw[:, [3, 0, 1, 2]].reshape(local.shape[:-2] + (4,))
    return rotations, translations
