"""Temporal consistency of depth signs, and a robust, smooth scale.

A bone's depth sign is a two-state chain over the frames. Keeping the sign from one frame
to the next costs nothing; flipping it makes the bone's depth jump by ``a + b`` instead of
``|a − b|`` (``a``, ``b``: its unsigned depth in the two frames), so under Gaussian
frame-to-frame depth changes of spread ``σ`` a flip costs ``2ab / σ²`` nats: free while the
bone crosses the image plane, prohibitive while it points steeply toward or away from the
camera. Posteriors of the chain come from the forward-backward algorithm, its messages
carried as log-odds in a compiled (numba) scan over the frames.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.ndimage import gaussian_filter1d, percentile_filter

#: Frames on each side of a frame that inform its scale.
SCALE_HALF_WINDOW = 15

#: Percentile of the per-frame scale bounds in the window taken as the scale.
SCALE_PERCENTILE = 75.0

#: Standard deviation of the Gaussian smoothing the scale, frames.
SCALE_SMOOTHING_FRAMES = 3.0

#: A message passes a flip that costs this many nats more than its own log-odds unchanged.
SETTLED_NATS = 40.0

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
    # One frame is never surer than MAX_LOG_ODDS: it keeps every message finite.
    evidence = np.clip(np.nan_to_num(log_odds), -MAX_LOG_ODDS, MAX_LOG_ODDS)
    posterior = np.empty(evidence.shape)
    _forward_backward(evidence, np.broadcast_to(flip_cost, evidence.shape), posterior)
    return np.clip(posterior, -MAX_LOG_ODDS, MAX_LOG_ODDS)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _log_add_exp(a: float, b: float) -> float:
    high = max(a, b)
    return high + math.log1p(math.exp(min(a, b) - high))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _pass_on(log_odds: float, flip_cost: float) -> float:
    """Log-odds of a chain's next state given its current state's log-odds.

    Equal to ``log_odds`` to within ``e^-SETTLED_NATS`` while the flip costs that much more
    than the odds (a steep bone keeps its sign), which skips the logarithms.
    """
    if flip_cost - abs(log_odds) > SETTLED_NATS:
        return log_odds
    return _log_add_exp(log_odds, -flip_cost) - _log_add_exp(log_odds - flip_cost, 0.0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _forward_backward(evidence, flip_cost, posterior):
    """Fill ``posterior`` ``(T, K)`` with the log-odds of the forward and backward messages.

    The messages of a two-state chain are carried as log-odds, one number per chain, so
    they neither overflow nor need rescaling however long the clip.
    """
    n_frames, n_chains = evidence.shape
    for k in range(n_chains):
        message = 0.0
        for t in range(n_frames - 1, -1, -1):
            posterior[t, k] = message
            message = _pass_on(evidence[t, k] + message, flip_cost[t, k])
        message = 0.0
        for t in range(n_frames):
            message = evidence[t, k] + (_pass_on(message, flip_cost[t, k]) if t else 0.0)
            posterior[t, k] += message


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
