"""The one place the library checks what callers hand it: hands, length units, point arrays.

Readers check files (:mod:`handdb.ingest`); these check arguments of the library's public
functions, and raise :class:`~handdb.errors.ParameterError` with the value received and
the values allowed.
"""

from __future__ import annotations

import numpy as np

from handdb.clip import HANDS, METERS_PER_UNIT
from handdb.errors import ParameterError


def check_hand(hand: str) -> str:
    """Return ``hand`` if it is ``"left"`` or ``"right"``; raise :class:`ParameterError`."""
    if hand not in HANDS:
        raise ParameterError(f"hand must be one of {', '.join(HANDS)}, got {hand!r}")
    return hand


def mm_per_unit(units: str) -> float:
    """Millimetres per length unit ``units`` (a key of :data:`handdb.clip.METERS_PER_UNIT`).

    Raises
    ------
    ParameterError
        If ``units`` is not a length unit handdb knows.
    """
    if units not in METERS_PER_UNIT:
        raise ParameterError(f"units must be one of {', '.join(METERS_PER_UNIT)}, got "
                             f"{units!r}")
    return METERS_PER_UNIT[units] * 1000.0


def check_fps(fps: float) -> float:
    """Return ``fps`` (frames per second) if it is positive; raise :class:`ParameterError`."""
    if not fps > 0:
        raise ParameterError(f"fps must be positive, got {fps}")
    return fps


def as_points(values: np.ndarray, n_joints: int, dims: int, name: str) -> np.ndarray:
    """``values`` as a ``(T, J, D) float64`` array of points, checked.

    Parameters
    ----------
    values
        Array-like of points over frames; NaN marks a missing point.
    n_joints
        ``J``, the joints of the skeleton the array follows.
    dims
        ``D``: 2 for image points, 3 for positions.
    name
        What the array is, for the message (``"markers"``, ``"uv"``).

    Returns
    -------
    numpy.ndarray
        A float64 array (a copy only when ``values`` was not one already).

    Raises
    ------
    ParameterError
        If the shape is not ``(T, J, D)`` with ``T >= 1``, or a value is infinite.
    """
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 3 or array.shape[1:] != (n_joints, dims) or len(array) == 0:
        raise ParameterError(f"{name} must be (frames, {n_joints}, {dims}), got shape "
                             f"{array.shape}")
    if np.isinf(array).any():
        raise ParameterError(f"{name} holds infinite values; mark a missing point with NaN")
    return array
