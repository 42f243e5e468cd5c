"""Joint rotations of a hand skeleton from its 3D joint positions.

Every joint carries an orthonormal frame whose local ``+Y`` axis points along the bone to
its child (the convention of Blender and of most rigs). The twist about that axis is what
positions alone do not fix; here it is fixed so that hinges stay hinges:

* A joint with several children (the palm root) takes the *palm frame*: ``+Y`` from the
  wrist towards the centroid of the four finger MCPs, ``+X`` towards the thumb side
  (along ``index_mcp - little_mcp`` made perpendicular to ``+Y``), ``+Z = X x Y``.
  Frames are right-handed for either hand, so ``+Z`` points out of the palm of a right
  hand and out of the back of a left one, and flexion has opposite signs for the two.
* A joint with one child aims ``+Y`` at it. Its ``+X`` is the *hinge axis* of its finger:
  the normal of the finger's flexion plane (the plane through its MCP, the joints after
  it and its tip), signed to agree with the palm's reference axis for that finger. The
  plane normal is trusted when the finger is bent (by :data:`PLANE_BLEND_BEND` or more)
  and the normal is within 75 degrees of the reference (:data:`PLANE_TRUSTED_COSINE`);
  below either, the axis blends smoothly into the reference axis, so a straight finger,
  or a tracker's finger bent sideways, cannot flip the axis and spin the frame. A finger's
  reference axis is the palm's ``+X``, across the palm. The thumb's is the palm normal
  ``Z_palm``: its nail faces sideways in a flat hand, so it bends across the palm, about
  an axis near the normal.
  Because PIP, DIP and IP frames share the plane normal as ``+X``, a finger bending in
  its plane turns those joints about their local ``X`` only: no twist, no spin.
* A leaf joint (a fingertip) keeps its parent's orientation.

Local transforms follow from the frames: a joint's local rotation is its frame expressed
in its parent's frame, and its local translation is its offset from the parent in the
parent's frame, scaled to the bone length. A joint whose parent has one child sits at
``(0, L, 0)``; a child of the palm root sits at ``L`` along its measured direction, so a
non-rigid palm is reproduced. The root's translation is its position.

Forward kinematics of these transforms reproduces the input positions exactly when the
bones have the given lengths. When noisy positions disagree with the lengths, every bone
keeps its measured direction and takes the given length, so joints further down a chain
move along with the corrected bones above them. With ``keep_lengths=False`` the bones
take their measured length at every frame instead (the translations stretch), and the
input positions are reproduced exactly whatever their lengths.

Quaternions are ``(w, x, y, z)``, scalar first, in float64, and each joint's quaternion
keeps one sign through the clip (no ``q -> -q`` flips between frames).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.errors import SkeletonError
from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import FINGERS, Skeleton
from handdb.vectors import cross, dot, norm

#: Below this bend (angle between consecutive finger bones), the flexion plane of a finger
#: is blended towards the palm's reference axis: radians.
PLANE_BLEND_BEND = np.deg2rad(5.0)

#: Below this cosine between a finger's flexion-plane normal and its reference axis, the
#: plane (then bent sideways, against anatomy) is blended towards the reference axis.
PLANE_TRUSTED_COSINE = np.cos(np.deg2rad(75.0))

#: Fingers whose MCPs define the palm frame, from the thumb side to the little side.
PALM_FINGERS: tuple[str, ...] = ("index", "middle", "ring", "little")

#: From handdb's camera frame (x right, y down, z away from the camera) to a Y-up,
#: right-handed frame (x right, y up, z towards the camera): 180 degrees about x.
CAMERA_TO_Y_UP = Rotation.from_rotvec([np.pi, 0.0, 0.0])

_EPS = 1e-12


@dataclass(frozen=True)
class JointMotion:
    """Local joint transforms of a skeleton over a clip.

    Attributes
    ----------
    rotations
        Local rotation of each joint relative to its parent's frame (the root's: relative
        to the world), ``(T, J, 4) float64`` unit quaternions ``(w, x, y, z)``.
    translations
        Local translation of each joint in its parent's frame, ``(T, J, 3) float64``, clip
        units; the root's entry is its world position.
    """

    rotations: np.ndarray
    translations: np.ndarray

    @property
    def n_frames(self) -> int:
        """Number of frames ``T``."""
        return self.rotations.shape[0]

    def root_translation(self, skeleton: Skeleton) -> np.ndarray:
        """World position of the root joint, ``(T, 3)``, clip units."""
        return self.translations[:, skeleton.root]


def child_counts(skeleton: Skeleton) -> np.ndarray:
    """Count the children of each joint: ``(J,) int64``."""
    return np.bincount(skeleton.parents[skeleton.parents >= 0], minlength=skeleton.n_joints)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(norm(v)[..., None], _EPS)


def _frame_from_axes(x_hint: np.ndarray, y: np.ndarray, fallback_hint: np.ndarray) -> np.ndarray:
    """Right-handed frames ``(..., 3, 3)`` (columns X, Y, Z) with ``Y`` along ``y``.

    ``X`` is ``x_hint`` made perpendicular to ``y``; where ``x_hint`` is (nearly) parallel
    to ``y``, ``fallback_hint`` stands in for it.
    """
    y = _unit(y)
    x = x_hint - dot(x_hint, y)[..., None] * y
    fallback = fallback_hint - dot(fallback_hint, y)[..., None] * y
    degenerate = norm(x)[..., None] < 1e-6 * np.maximum(norm(x_hint)[..., None], _EPS)
    x = _unit(np.where(degenerate, fallback, x))
    return np.stack([x, y, cross(x, y)], axis=-1)


def palm_joints(skeleton: Skeleton) -> tuple[int, np.ndarray]:
    """Index of the wrist and of the MCPs of :data:`PALM_FINGERS`, thumb side first."""
    roles = np.array(skeleton.roles)
    fingers = np.array(skeleton.fingers)
    wrist = np.flatnonzero(roles == "wrist")
    mcps = [np.flatnonzero((roles == "mcp") & (fingers == f)) for f in PALM_FINGERS]
    if len(wrist) != 1 or any(len(m) != 1 for m in mcps):
        raise SkeletonError(
            f"skeleton '{skeleton.name}' needs one wrist and one MCP on each of "
            f"{', '.join(PALM_FINGERS)} to define the palm frame"
        )
    return int(wrist[0]), np.array([int(m[0]) for m in mcps])


def palm_frame(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Orientation of the palm at every frame.

    Parameters
    ----------
    xyz
        Joint positions, ``(T, J, 3) float64``, any length unit.
    skeleton
        Skeleton of ``xyz``; it needs a wrist and the MCPs of the four fingers.

    Returns
    -------
    numpy.ndarray
        ``(T, 3, 3)`` rotation matrices whose columns are the palm's ``X`` (towards the
        thumb side), ``Y`` (wrist to the MCP centroid) and ``Z = X x Y`` in the frame of
        ``xyz``.
    """
    wrist, mcps = palm_joints(skeleton)
    y = xyz[:, mcps].mean(axis=1) - xyz[:, wrist]
    lateral = xyz[:, mcps[0]] - xyz[:, mcps[-1]]
    return _frame_from_axes(lateral, y, cross(y, np.array([0.0, 0.0, 1.0])))


def _finger_hinge_axes(
    xyz: np.ndarray, skeleton: Skeleton, palm: np.ndarray
) -> dict[str, np.ndarray]:
    """Hinge axis of every finger, ``finger -> (T, 3)`` unit vectors (see module doc)."""
    axes = {}
    for finger in FINGERS:
        chain = skeleton.finger_chain(finger)
        if len(chain) == 0:
            continue
        reference = palm[..., 2] if finger == "thumb" else palm[..., 0]
        roles = [skeleton.roles[j] for j in chain]
        plane_joints = chain[roles.index("mcp"):] if "mcp" in roles else chain
        bones = np.diff(xyz[:, plane_joints], axis=1)
        normal = cross(bones[:, :-1], bones[:, 1:]).sum(axis=1)
        lengths = norm(bones)
        scale = (lengths[:, :-1] * lengths[:, 1:]).sum(axis=1)
        bend = norm(normal) / np.maximum(scale, _EPS)
        cosine = dot(_unit(normal), reference)
        weight = (np.clip(bend / np.sin(PLANE_BLEND_BEND), 0.0, 1.0)
                  * np.clip(np.abs(cosine) / PLANE_TRUSTED_COSINE, 0.0, 1.0))[:, None]
        signed_normal = np.where(cosine < 0, -1.0, 1.0)[:, None] * _unit(normal)
        axes[finger] = _unit(weight * signed_normal + (1 - weight) * reference)
    return axes


def joint_frames(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """World orientation of every joint's frame (see the module doc for the rules).

    Parameters
    ----------
    xyz
        Joint positions, ``(T, J, 3) float64``, any length unit, no NaN.
    skeleton
        Skeleton of ``xyz``.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 3, 3)`` rotation matrices, columns the joint's ``X``, ``Y``, ``Z`` axes.
    """
    palm = palm_frame(xyz, skeleton)
    hinge_axes = _finger_hinge_axes(xyz, skeleton, palm)
    frames = np.empty((*xyz.shape[:2], 3, 3))
    counts = child_counts(skeleton)
    # every joint with one child in one call: the arithmetic is per frame and joint, so
    # the frames are those of one call per joint, without its fixed cost fifteen times
    aiming = np.flatnonzero(counts == 1)
    if len(aiming):
        hints = np.stack([hinge_axes.get(skeleton.fingers[joint], palm[..., 0])
                          for joint in aiming], axis=1)                    # (T, K, 3)
        children = np.array([skeleton.children(int(j))[0] for j in aiming], dtype=np.intp)
        bones = xyz[:, children] - xyz[:, aiming]
        fallback = np.broadcast_to(palm[:, None, :, 2], bones.shape)
        frames[:, aiming] = _frame_from_axes(hints, bones, fallback)
    frames[:, counts > 1] = palm[:, None]
    for joint in np.flatnonzero(counts == 0):
        frames[:, joint] = frames[:, skeleton.parents[joint]]
    return frames


def _continuous_sign(quaternions: np.ndarray) -> np.ndarray:
    """Flip quaternions ``(T, J, 4)`` so consecutive frames lie in the same hemisphere."""
    same = dot(quaternions[1:], quaternions[:-1]) >= 0
    signs = np.cumprod(np.where(same, 1.0, -1.0), axis=0)
    return quaternions * np.concatenate([np.ones((1, *signs.shape[1:])), signs])[..., None]


def joint_rotations(
    xyz: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray, *, keep_lengths: bool = True
) -> JointMotion:
    """Local joint rotations and translations that pose ``skeleton`` like ``xyz``.

    Parameters
    ----------
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, no NaN.
    skeleton
        Skeleton of ``xyz``.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units (see
        :func:`~handdb.hand.skeletons.bone_length_array`).
    keep_lengths
        ``True``: every bone has its length from ``bone_lengths``. ``False``: every bone
        has its length measured in ``xyz`` at each frame.

    Returns
    -------
    JointMotion
        Local rotations ``(T, J, 4)`` ``(w, x, y, z)`` and translations ``(T, J, 3)``. Their
        forward kinematics (:func:`motion_positions`) gives back ``xyz`` when its bones
        have ``bone_lengths`` or ``keep_lengths`` is ``False``; otherwise the joints reached
        by keeping each bone's direction.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if not np.isfinite(xyz).all():
        raise ValueError("joint positions contain NaN or inf; fill gaps before posing")
    frames = joint_frames(xyz, skeleton)
    parents = skeleton.parents
    root = skeleton.root
    local = frames.copy()
    has_parent = parents >= 0
    parent_frames = frames[:, parents[has_parent]]
    local[:, has_parent] = np.swapaxes(parent_frames, -1, -2) @ frames[:, has_parent]

    translations = np.zeros(xyz.shape)
    translations[:, root] = xyz[:, root]
    bone_parents, bone_children = np.array(skeleton.bones, dtype=np.intp).reshape(-1, 2).T
    offsets = np.einsum("tbji,tbj->tbi", frames[:, bone_parents],
                        xyz[:, bone_children] - xyz[:, bone_parents])
    lengths = (np.broadcast_to(bone_lengths[bone_children], offsets.shape[:2]) if keep_lengths
               else norm(offsets))
    along_bone = child_counts(skeleton)[bone_parents] == 1
    translations[:, bone_children[along_bone], 1] = lengths[:, along_bone]
    translations[:, bone_children[~along_bone]] = (lengths[:, ~along_bone, None]
                                                   * _unit(offsets[:, ~along_bone]))

    # Every frame is built orthonormal and right-handed, so scipy's projection onto the
    # rotations (an SVD per matrix) has nothing to correct.
    flat = Rotation.from_matrix(local.reshape(-1, 3, 3), assume_valid=True)
    quaternions = flat.as_quat(scalar_first=True).reshape(*xyz.shape[:2], 4)
    return JointMotion(rotations=_continuous_sign(quaternions), translations=translations)


def world_transforms(motion: JointMotion, skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Forward kinematics: world orientation and position of every joint.

    Parameters
    ----------
    motion
        Local joint transforms, ``T`` frames.
    skeleton
        Skeleton of ``motion``.

    Returns
    -------
    orientations : numpy.ndarray
        ``(T, J, 3, 3)`` rotation matrices (columns: the joint's axes in the world).
    positions : numpy.ndarray
        ``(T, J, 3)`` joint positions, clip units.
    """
    local = Rotation.from_quat(motion.rotations.reshape(-1, 4), scalar_first=True)
    local = local.as_matrix().reshape(*motion.rotations.shape[:2], 3, 3)
    orientations = np.empty_like(local)
    positions = np.empty(motion.translations.shape)
    for joint, parent in enumerate(skeleton.parents):
        if parent < 0:
            orientations[:, joint] = local[:, joint]
            positions[:, joint] = motion.translations[:, joint]
            continue
        orientations[:, joint] = orientations[:, parent] @ local[:, joint]
        positions[:, joint] = positions[:, parent] + np.einsum(
            "tij,tj->ti", orientations[:, parent], motion.translations[:, joint])
    return orientations, positions


def motion_positions(motion: JointMotion, skeleton: Skeleton) -> np.ndarray:
    """World joint positions ``(T, J, 3)`` of ``motion``, clip units."""
    return world_transforms(motion, skeleton)[1]


def rest_positions(skeleton: Skeleton, bone_lengths: np.ndarray) -> np.ndarray:
    """Joint positions of the rest pose: the average hand with straight fingers.

    The average hand of :func:`handdb.hand.shape.mean_shape` with the given bone lengths
    (each bone along its rest direction, from the root), expressed in its own palm frame,
    so the root's rest rotation is the identity: fingers along ``+Y``, thumb towards
    ``+X``, palm normal ``+Z``; the root at the origin.

    Parameters
    ----------
    skeleton
        The skeleton.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.

    Returns
    -------
    numpy.ndarray
        ``(J, 3) float64``, clip units.
    """
    shape = mean_shape().with_bone_lengths(skeleton, np.asarray(bone_lengths, np.float64))
    positions = shape.positions(skeleton)
    positions = positions - positions[skeleton.root]
    palm = palm_frame(positions[None], skeleton)[0]
    return positions @ palm


def rest_pose(skeleton: Skeleton, bone_lengths: np.ndarray) -> JointMotion:
    """Local transforms of the rest pose (:func:`rest_positions`), one frame (``T = 1``)."""
    return joint_rotations(rest_positions(skeleton, bone_lengths)[None], skeleton, bone_lengths)


def turn_root(motion: JointMotion, skeleton: Skeleton, rotation: Rotation) -> JointMotion:
    """``motion`` seen in a frame turned by ``rotation`` (e.g. :data:`CAMERA_TO_Y_UP`).

    Only the root's rotation and translation change: every other local transform is
    relative to its parent and stays as it is.
    """
    root = skeleton.root
    rotations = motion.rotations.copy()
    translations = motion.translations.copy()
    root_rotation = Rotation.from_quat(rotations[:, root], scalar_first=True)
    rotations[:, root] = (rotation * root_rotation).as_quat(scalar_first=True)
    translations[:, root] = rotation.apply(translations[:, root])
    return JointMotion(rotations=_continuous_sign(rotations), translations=translations)
