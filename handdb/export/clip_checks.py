"""What the exports check of the clip they are handed, before posing or writing it."""

from __future__ import annotations

import numpy as np

from handdb.checks import as_points, check_fps, check_hand, mm_per_unit
from handdb.errors import ParameterError, StageError
from handdb.hand.skeletons import Skeleton


def check_skinned_clip(skeleton: Skeleton, xyz: np.ndarray, bone_lengths: np.ndarray, *,
                       fps: float, units: str, hand: str) -> tuple[np.ndarray, np.ndarray]:
    """Check the arguments of a skinned export and return its arrays as float64.

    Parameters
    ----------
    skeleton, xyz, bone_lengths, fps, units, hand
        As for :func:`handdb.export.usd.export_clip_usd` and
        :func:`handdb.export.gltf.export_clip_gltf`; ``xyz`` may hold NaN.

    Returns
    -------
    tuple of numpy.ndarray
        ``xyz`` as ``(T, J, 3) float64`` and ``bone_lengths`` as ``(J,) float64``.

    Raises
    ------
    ParameterError
        On an unknown unit or hand, a non-positive fps, or arrays whose shapes do not match
        ``skeleton``.
    """
    mm_per_unit(units)
    check_hand(hand)
    check_fps(fps)
    positions = as_points(xyz, skeleton.n_joints, 3, "xyz")
    lengths = np.asarray(bone_lengths, dtype=np.float64)
    if lengths.shape != (skeleton.n_joints,):
        raise ParameterError(
            f"bone_lengths must be ({skeleton.n_joints},), got {lengths.shape}")
    return positions, lengths


def unplaced_frames(xyz: np.ndarray) -> int:
    """Frames of ``xyz`` ``(T, J, 3)`` with a joint that has no 3D position (NaN)."""
    return int((~np.isfinite(xyz).all(axis=(1, 2))).sum())


def require_filled(xyz: np.ndarray, source: str) -> None:
    """Raise unless every frame of ``xyz`` places every joint, as posing a skeleton needs.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions, clip units; NaN where a joint has no position.
    source
        What the positions are, to open the message (``"clip 'rapid-s01'"``, a file path).

    Raises
    ------
    StageError
        If a frame has a joint without a 3D position (fill the gaps first).
    """
    missing = unplaced_frames(xyz)
    if missing:
        raise StageError(f"{source}: {missing} of {len(xyz)} frames have joints "
                         "without a 3D position; fill the gaps before exporting")


def placed_frames(xyz: np.ndarray, source: str) -> np.ndarray:
    """The frames of ``xyz`` that place every joint, as a posed animation can key them.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions, clip units; NaN where a joint has no position.
    source
        What the positions are, to open the message (``"clip 'rapid-s01'"``, a file path).

    Returns
    -------
    numpy.ndarray
        ``(n,) int64`` frame numbers, increasing, ``n >= 1``.

    Raises
    ------
    StageError
        If no frame places every joint.
    """
    frames = np.flatnonzero(np.isfinite(xyz).all(axis=(1, 2)))
    if len(frames) == 0:
        raise StageError(f"{source}: none of its {len(xyz)} frames places every joint in 3D; "
                         "fill the gaps before exporting")
    return frames
