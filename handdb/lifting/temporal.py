"""Temporal consistency of depth signs and a robust, smooth scale.

A bone's depth sign can only change while the bone passes through the image plane, that
is where its unsigned depth ``|dZ|`` has a local minimum over time. Between two such minima
the sign is constant, so the evidence of every frame of the run can be pooled into one
decision. This is the exact solution of a two-state chain whose transition cost is zero at
the minima and infinite elsewhere, computed with array operations instead of a per-frame
loop.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d, percentile_filter

#: Frames on each side of a frame that inform its scale.
SCALE_HALF_WINDOW = 15

#: Percentile of the per-frame scale bounds in the window taken as the scale.
SCALE_PERCENTILE = 75.0

#: Standard deviation of the Gaussian smoothing the scale, frames.
SCALE_SMOOTHING_FRAMES = 3.0


def run_labels(magnitude: np.ndarray) -> np.ndarray:
    """Label the runs of frames between local minima of an unsigned depth.

    Parameters
    ----------
    magnitude
        ``(T, ...) float64``: ``|dZ|`` of one or more bones (time on axis 0).

    Returns
    -------
    numpy.ndarray
        ``(T, ...) int64``: a run number per frame, increasing over time, unique per column
        (labels of different columns never coincide). A frame at a local minimum starts a
        new run.
    """
    m = np.nan_to_num(magnitude, nan=0.0)
    falling = np.zeros(m.shape, dtype=bool)
    falling[1:] = m[1:] <= m[:-1]
    rising_next = np.ones(m.shape, dtype=bool)
    rising_next[:-1] = m[1:] > m[:-1]
    minimum = falling & rising_next
    minimum[0] = True
    labels = np.cumsum(minimum.reshape(len(m), -1), axis=0)
    offsets = np.cumsum(labels[-1]) - labels[-1]
    return (labels + offsets).reshape(m.shape) if len(m) else labels.reshape(m.shape)


def pooled_log_odds(log_odds: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Sum per-frame log-odds over each run and hand every frame its run's total.

    Parameters
    ----------
    log_odds
        ``(T, ...) float64``, per-frame evidence for the positive sign.
    labels
        ``(T, ...) int64`` from :func:`run_labels`.

    Returns
    -------
    numpy.ndarray
        ``(T, ...) float64``.
    """
    flat = labels.ravel()
    totals = np.bincount(flat, weights=np.nan_to_num(log_odds).ravel(),
                         minlength=int(flat.max(initial=0)) + 1)
    return totals[labels]


def smooth_scale(bounds: np.ndarray) -> np.ndarray:
    """A scale per frame from per-frame lower bounds, robust to outliers and smooth.

    Parameters
    ----------
    bounds
        ``(T,) float64``: for each frame a lower bound of its scale (eq. 6); NaN where
        none.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``: an upper percentile of the bounds in a window around each frame
        (a bound is tight only for frames where some bone lies in the image plane), then
        Gaussian-smoothed. NaN frames take their nearest finite neighbour's bound.
    """
    finite = np.isfinite(bounds)
    if not finite.any():
        return np.full(bounds.shape, np.nan)
    index = np.arange(len(bounds))
    filled = np.interp(index, index[finite], bounds[finite])
    window = 2 * SCALE_HALF_WINDOW + 1
    upper = percentile_filter(filled, SCALE_PERCENTILE, size=window, mode="nearest")
    return gaussian_filter1d(upper, SCALE_SMOOTHING_FRAMES, mode="nearest")


def sigmoid(x: np.ndarray) -> np.ndarray:
    """Logistic function, numerically safe for large ``|x|``."""
    return 0.5 * (1.0 + np.tanh(0.5 * x))
