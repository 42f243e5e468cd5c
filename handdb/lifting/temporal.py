"""Temporal consistency of depth signs, and a robust, smooth scale.

A bone's depth sign is a two-state chain over the frames. Keeping the sign from one frame
to the next costs nothing; flipping it makes the bone's depth jump by ``a + b`` instead of
``|a − b|`` (``a``, ``b``: its unsigned depth in the two frames), so under Gaussian
frame-to-frame depth changes of spread ``σ`` a flip costs ``2ab / σ²`` nats: free while the
bone crosses the image plane, prohibitive while it points steeply toward or away from the
camera. Posteriors of the chain come from the forward-backward algorithm, written as
prefix products of 2×2 matrices computed by recursive doubling, so the work is array
operations over all frames at once (``log2 T`` levels), never a loop over frames.
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

#: Posterior log-odds are clipped to this magnitude (a probability of 1 − 1e-13).
MAX_LOG_ODDS = 30.0


def flip_costs(magnitude: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """Cost in nats of flipping each chain's sign between consecutive frames.

    Parameters
    ----------
    magnitude
        ``(T, K) float64``: unsigned depth of ``K`` chains (bones, or the palm's tilt).
    floor
        ``(K,) float64``: smallest spread of frame-to-frame depth change, same units.

    Returns
    -------
    numpy.ndarray
        ``(T, K) float64``: ``2ab / σ²`` between frame ``t − 1`` and ``t`` (row 0: 0), with
        ``σ²`` the chain's mean squared frame-to-frame change of ``magnitude`` plus
        ``floor²``.
    """
    m = np.nan_to_num(magnitude)
    spread = np.mean(np.diff(m, axis=0) ** 2, axis=0) + floor**2 if len(m) > 1 else floor**2
    cost = np.zeros(m.shape)
    cost[1:] = 2.0 * m[1:] * m[:-1] / spread
    return cost


def _product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Multiply stacks of 2×2 matrices, ``a @ b``, rescaled to a largest entry of 1.

    Matrices are held entry-major, ``(2, 2, ...)``, so every entry is one contiguous
    array and the products are plain elementwise operations.
    """
    out = np.stack([np.stack([a[0, 0] * b[0, 0] + a[0, 1] * b[1, 0],
                              a[0, 0] * b[0, 1] + a[0, 1] * b[1, 1]]),
                    np.stack([a[1, 0] * b[0, 0] + a[1, 1] * b[1, 0],
                              a[1, 0] * b[0, 1] + a[1, 1] * b[1, 1]])])
    return out / np.maximum(np.maximum(out[0, 0], out[0, 1]),
                            np.maximum(out[1, 0], out[1, 1]))


def _prefix_products(matrices: np.ndarray) -> np.ndarray:
    """``out[:, :, t] = m[:, :, 0] @ ... @ m[:, :, t]`` (each rescaled), by recursive doubling.

    ``matrices`` is ``(2, 2, T, ...)``, entry-major (see :func:`_product`).
    """
    n = matrices.shape[2]
    if n == 1:
        return matrices
    odd = _prefix_products(_product(matrices[:, :, 0 : n - 1 : 2], matrices[:, :, 1:n:2]))
    out = np.empty_like(matrices)
    out[:, :, 0] = matrices[:, :, 0]
    out[:, :, 1::2] = odd
    out[:, :, 2::2] = _product(odd[:, :, : (n - 1) // 2], matrices[:, :, 2::2])
    return out


def sign_posterior(log_odds: np.ndarray, flip_cost: np.ndarray) -> np.ndarray:
    """Posterior log-odds of the positive sign of each chain, given every frame.

    Parameters
    ----------
    log_odds
        ``(T, K) float64``: each frame's own evidence for the positive sign.
    flip_cost
        ``(T, K) float64``: cost of flipping between frame ``t − 1`` and ``t``
        (:func:`flip_costs`).

    Returns
    -------
    numpy.ndarray
        ``(T, K) float64``.
    """
    n_frames = len(log_odds)
    if n_frames == 0:
        return np.zeros(log_odds.shape)
    # One frame is never surer than MAX_LOG_ODDS: unbounded evidence (a state of zero
    # likelihood) would let consecutive steps annihilate and the scan divide 0 by 0.
    half = 0.5 * np.clip(np.nan_to_num(log_odds), -MAX_LOG_ODDS, MAX_LOG_ODDS)
    peak = np.abs(half)                     # each step scaled to a largest entry of 1
    flip = -np.broadcast_to(flip_cost, half.shape) - peak
    # step[i, j, t]: from state i at frame t - 1 to state j at frame t (0: positive).
    emission = np.exp(np.stack([half - peak, -half - peak]))
    step = np.stack([np.stack([emission[0], np.exp(flip - half)]),
                     np.stack([np.exp(flip + half), emission[1]])])       # (2, 2, T, K)
    start = emission[:, 0]                                              # (2, K)
    forward = np.empty((2,) + half.shape)
    forward[:, 0] = start
    backward = np.ones((2,) + half.shape)
    if n_frames > 1:
        prefix = _prefix_products(step[:, :, 1:])
        forward[:, 1:] = start[0] * prefix[0] + start[1] * prefix[1]
        suffix = _prefix_products(step[:, :, :0:-1].transpose(1, 0, 2, 3))[:, :, ::-1]
        backward[:, :-1] = suffix[0] + suffix[1]
    with np.errstate(divide="ignore"):
        log_joint = np.log(forward) + np.log(backward)
    return np.clip(log_joint[0] - log_joint[1], -MAX_LOG_ODDS, MAX_LOG_ODDS)


def smooth_scale(bounds: np.ndarray, percentile: float = SCALE_PERCENTILE,
                 half_window: int = SCALE_HALF_WINDOW) -> np.ndarray:
    """Estimate a scale per frame from per-frame lower bounds, robust and smooth.

    Parameters
    ----------
    bounds
        ``(T,) float64``: for each frame a lower bound of its scale (eq. 6); NaN where
        none.
    percentile
        Percentile of the bounds in the window taken as the scale.
    half_window
        Frames on each side of a frame that inform its scale.

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
    upper = percentile_filter(filled, percentile, size=2 * half_window + 1, mode="nearest")
    return gaussian_filter1d(upper, SCALE_SMOOTHING_FRAMES, mode="nearest")


def sigmoid(x: np.ndarray | float) -> np.ndarray:
    """Logistic function, numerically safe for large ``|x|``."""
    return 0.5 * (1.0 + np.tanh(0.5 * x))
