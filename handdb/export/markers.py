"""Joint positions as the marker trajectories TRC and C3D files hold: checked, turned Y-up."""

from __future__ import annotations

import numpy as np

from handdb.checks import check_fps, mm_per_unit
from handdb.errors import ParameterError
from handdb.export.rotations import CAMERA_TO_Y_UP
from handdb.hand.skeletons import Skeleton


def y_up_markers(xyz: np.ndarray, skeleton: Skeleton, fps: float, units: str) -> np.ndarray:
    """Check a clip's joint positions and turn them to the Y-up frame of every export.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions, clip units, handdb's camera frame; NaN where
        a joint has no position.
    skeleton
        Skeleton of ``xyz``.
    fps
        Frames per second, > 0.
    units
        ``mm``, ``cm``, ``m`` or ``in``.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 3) float64``, clip units, turned by
        :data:`handdb.export.rotations.CAMERA_TO_Y_UP`; NaN where ``xyz`` has any.

    Raises
    ------
    ParameterError
        On a non-positive fps, an unknown unit or ``xyz`` not shaped ``(T, J, 3)``.
    """
    mm_per_unit(units)
    check_fps(fps)
    xyz = np.asarray(xyz, dtype=np.float64)
    if xyz.ndim != 3 or xyz.shape[1:] != (skeleton.n_joints, 3):
        raise ParameterError(f"xyz must be (T, {skeleton.n_joints}, 3), got {xyz.shape}")
    return CAMERA_TO_Y_UP.apply(xyz.reshape(-1, 3)).reshape(xyz.shape)
