"""Camera projections of camera-frame points (x right, y down, z away from the camera)."""

from __future__ import annotations

import numpy as np


def project_orthographic(
    xyz: np.ndarray, scale: float, center: tuple[float, float] = (0.0, 0.0)
) -> np.ndarray:
    """Scaled orthographic projection: ``u = scale * x + cx``, ``v = scale * y + cy``.

    Parameters
    ----------
    xyz
        ``(..., 3) float64`` points, any length unit.
    scale
        Pixels per length unit.
    center
        ``(cx, cy)`` pixels: where the camera axis meets the image.

    Returns
    -------
    (..., 2) float64
        Pixel coordinates.
    """
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number of pixels per unit, got {scale}")
    return scale * np.asarray(xyz, dtype=np.float64)[..., :2] + np.asarray(center, dtype=np.float64)


def project_pinhole(xyz: np.ndarray, fx: float, fy: float, cx: float, cy: float) -> np.ndarray:
    """Pinhole projection: ``u = fx * x / z + cx``, ``v = fy * y / z + cy``.

    Parameters
    ----------
    xyz
        ``(..., 3) float64`` points in front of the camera (``z > 0``), any length unit.
    fx, fy
        Focal lengths, pixels.
    cx, cy
        Principal point, pixels.

    Returns
    -------
    (..., 2) float64
        Pixel coordinates.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    depth = xyz[..., 2]
    if np.any(depth <= 0):
        raise ValueError(
            f"{int(np.sum(depth <= 0))} points are not in front of the camera (z <= 0); "
            "move the hand further from the camera"
        )
    focal = np.array([fx, fy])
    return focal * xyz[..., :2] / depth[..., None] + np.array([cx, cy])
