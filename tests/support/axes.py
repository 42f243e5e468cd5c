"""Expected positions in the Y-up frame every export writes, for tests."""

import numpy as np

from handdb.export.rotations import CAMERA_TO_Y_UP


def y_up(xyz: np.ndarray) -> np.ndarray:
    """Points ``(..., 3)`` in handdb's camera frame turned by ``CAMERA_TO_Y_UP``, same shape."""
    return CAMERA_TO_Y_UP.apply(np.reshape(xyz, (-1, 3))).reshape(np.shape(xyz))
