"""Export a clip's joint rotations as BVH (Biovision Hierarchy), the mocap tools' format.

The hierarchy is the skeleton's, written depth first. Each joint's ``OFFSET`` is its
rest-pose translation (:func:`handdb.export.rotations.rest_pose`): ``(0, L, 0)`` along the
parent's ``+Y`` for a joint down a finger, ``L`` along the rest direction for a child of
the palm root. A fingertip also gets an ``End Site`` :data:`END_SITE_RATIO` of its bone
length further along ``+Y``, so tools draw its last bone.

Channels. The root has ``Xposition Yposition Zposition`` (its world position) and so has
every child of the palm root, whose offset from the root changes when the measured palm is
not rigid; for a joint with position channels, they replace its ``OFFSET``. Every joint has
rotation channels ``Xrotation Zrotation Yrotation``: intrinsic X-Z-Y Euler angles in
degrees, i.e. the local rotation matrix is ``Rx(x) @ Rz(z) @ Ry(y)``. That order keeps the
middle angle on the abduction axis ``Z``, which never nears 90 degrees in a hand, so
finger flexion (about ``X``) never hits gimbal lock; angles are unwrapped over time.

Bones are rigid: they keep their measured directions and take the given lengths
(:func:`handdb.export.rotations.joint_rotations` with ``keep_lengths=True``), as BVH readers
expect constant offsets.

Axes and units: Y-up as in USD export (handdb's camera frame turned 180 degrees about
``x``, :data:`handdb.export.rotations.CAMERA_TO_Y_UP`). BVH has no unit field (and no
comment syntax to state one), and readers take its numbers in their own scene unit:
Blender's importer (``global_scale=1``) reads them as metres, its scene unit. So every
offset and position channel is in metres, whatever the clip's units, and a hand imports at
its true size with the default settings. ``Frame Time`` is ``1 / fps`` seconds.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.checks import check_fps, mm_per_unit
from handdb.clip import METERS_PER_UNIT
from handdb.export.clip_checks import require_filled
from handdb.export.rotations import (
    CAMERA_TO_Y_UP,
    JointMotion,
    child_counts,
    joint_rotations,
    rest_pose,
    turn_root,
)
from handdb.hand.skeletons import Skeleton

#: Intrinsic Euler order of the rotation channels (scipy's upper-case notation).
EULER_ORDER = "XZY"

#: Length of a fingertip's End Site as a fraction of the tip's bone length.
END_SITE_RATIO = 0.5

_POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
_ROTATION_CHANNELS = tuple(f"{axis}rotation" for axis in EULER_ORDER)
_INDENT = "  "


def depth_first_order(skeleton: Skeleton) -> list[int]:
    """Joint indices in the order BVH lists them: each joint, then its subtrees."""
    order: list[int] = []
    stack = [skeleton.root]
    while stack:
        joint = stack.pop()
        order.append(joint)
        stack.extend(reversed(skeleton.children(joint).tolist()))
    return order


def _has_position_channels(skeleton: Skeleton) -> np.ndarray:
    """``(J,) bool``: the root and every child of a joint with several children."""
    parents = skeleton.parents
    return (parents < 0) | (child_counts(skeleton)[np.maximum(parents, 0)] > 1)


def _hierarchy(skeleton: Skeleton, offsets: np.ndarray, bone_lengths: np.ndarray) -> str:
    positioned = _has_position_channels(skeleton)
    lines = ["HIERARCHY"]

    def write(joint: int, depth: int) -> None:
        pad = _INDENT * depth
        keyword = "ROOT" if skeleton.parents[joint] < 0 else "JOINT"
        channels = (_POSITION_CHANNELS if positioned[joint] else ()) + _ROTATION_CHANNELS
        lines.extend([
            f"{pad}{keyword} {skeleton.joints[joint]}",
            f"{pad}{{",
            f"{pad}{_INDENT}OFFSET {' '.join(f'{v:.9f}' for v in offsets[joint])}",
            f"{pad}{_INDENT}CHANNELS {len(channels)} {' '.join(channels)}",
        ])
        children = skeleton.children(joint)
        for child in children:
            write(int(child), depth + 1)
        if len(children) == 0:
            end = END_SITE_RATIO * bone_lengths[joint]
            lines.extend([f"{pad}{_INDENT}End Site", f"{pad}{_INDENT}{{",
                          f"{pad}{_INDENT * 2}OFFSET 0.000000000 {end:.9f} 0.000000000",
                          f"{pad}{_INDENT}}}"])
        lines.append(f"{pad}}}")

    write(skeleton.root, 0)
    return "\n".join(lines) + "\n"


def motion_channels(motion: JointMotion, skeleton: Skeleton) -> np.ndarray:
    """Return the MOTION block's numbers: a row per frame, joints in :func:`depth_first_order`.

    Parameters
    ----------
    motion
        Local joint transforms, already in the file's axes, ``T`` frames.
    skeleton
        Skeleton of ``motion``.

    Returns
    -------
    numpy.ndarray
        ``(T, C) float64``: per joint its position channels (clip units) if it has them,
        then its rotation channels (degrees, :data:`EULER_ORDER`).
    """
    n_frames, n_joints = motion.rotations.shape[:2]
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock detected")
        euler = Rotation.from_quat(motion.rotations.reshape(-1, 4), scalar_first=True).as_euler(
            EULER_ORDER, degrees=True)
    euler = np.unwrap(euler.reshape(n_frames, n_joints, 3), period=360.0, axis=0)
    positioned = _has_position_channels(skeleton)
    columns = []
    for joint in depth_first_order(skeleton):
        if positioned[joint]:
            columns.append(motion.translations[:, joint])
        columns.append(euler[:, joint])
    return np.concatenate(columns, axis=1)


def export_clip_bvh(
    path: str | Path,
    *,
    skeleton: Skeleton,
    xyz: np.ndarray,
    bone_lengths: np.ndarray,
    fps: float,
    units: str,
    rotations: JointMotion | None = None,
) -> Path:
    """Write a clip's motion as a BVH file.

    Parameters
    ----------
    path
        Output ``.bvh`` file; its folder must exist.
    skeleton
        Skeleton of ``xyz``.
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, handdb's camera frame, no NaN.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.
    fps
        Frames per second, > 0.
    units
        Units of ``xyz`` and ``bone_lengths`` (``mm``, ``cm``, ``m`` or ``in``); the file
        is in metres.
    rotations
        Local joint transforms to export instead of those computed from ``xyz``, clip
        units.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    StageError
        If ``xyz`` has frames with missing joints (fill gaps first).
    """
    path = Path(path)
    mm_per_unit(units)
    check_fps(fps)
    bone_lengths = np.asarray(bone_lengths, dtype=np.float64)
    if rotations is None:
        require_filled(xyz, str(path))
        rotations = joint_rotations(xyz, skeleton, bone_lengths)
    metres = METERS_PER_UNIT[units]
    offsets = metres * rest_pose(skeleton, bone_lengths).translations[0]
    offsets[skeleton.root] = 0.0
    turned = turn_root(rotations, skeleton, CAMERA_TO_Y_UP)
    in_metres = JointMotion(turned.rotations, metres * turned.translations)
    channels = motion_channels(in_metres, skeleton)
    text = io.StringIO()
    text.write(_hierarchy(skeleton, offsets, metres * bone_lengths))
    text.write(f"MOTION\nFrames: {len(channels)}\nFrame Time: {1.0 / fps:.8f}\n")
    # Nine significant digits: below a micrometre in metres, 1e-6 degree in angles.
    np.savetxt(text, channels, fmt="%.9g")
    path.write_text(text.getvalue())
    return path
