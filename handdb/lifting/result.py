"""What a lifting method returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LiftResult:
    """A clip lifted to 3D.

    Attributes
    ----------
    xyz
        ``(T, J, 3) float64``, clip units, camera frame (x right, y down, z away from the
        camera). Orthographic: ``x = u / s``, ``y = v / s`` and the root at ``z = 0``;
        pinhole: metric positions along the rays. NaN where the joint (or a joint between
        it and the root) has no image point.
    sign_confidence
        ``(T, J) float64`` in [0.5, 1]: probability that the bone ending at each joint has
        the depth sign chosen; NaN at the root, and everywhere for methods without a
        model of their own uncertainty (the thesis's rules).
    length_inconsistency
        ``(T, J) float64`` >= 0, clip units: how far the bone ending at each joint had to
        give to fit its track (the discriminant was clamped at zero); 0 at the root.
    scale
        ``(T,) float64``: orthographic scale, pixels per clip unit; NaN for a pinhole lift.
    method
        Name of the method that produced the result.
    mirror_ambiguous
        True when the clip's evidence does not settle the clip-wide mirror (every depth
        sign flipped at once); ``note`` then says so.
    mirror_log_odds
        Calibrated log-odds, nats, of the depth signs chosen over all of them flipped at
        once (:mod:`handdb.lifting.evidence`); ``None`` for methods that do not weigh the
        mirror. Lifted image by image: the least settled image's.
    note
        Human-readable remarks about the result (empty when there are none).
    """

    xyz: np.ndarray
    sign_confidence: np.ndarray
    length_inconsistency: np.ndarray
    scale: np.ndarray
    method: str
    mirror_ambiguous: bool = False
    mirror_log_odds: float | None = None
    note: str = ""
