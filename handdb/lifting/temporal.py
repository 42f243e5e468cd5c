"""Temporal consistency of depth signs, and a robust, smooth scale.

A bone's depth sign is a two-state chain over the frames, and so is the palm's tilt. What
ties consecutive frames together is that the signed value (a bone's depth, the depths of
the palm's joints) moves smoothly: under a constant-velocity model its second
frame-to-frame difference is Gaussian. Away from the image plane this makes a flip
prohibitive (the value would jump by twice its size); where a bone crosses the image
plane it tells a motion that goes on through it (``+4, +2, −1, −3``) from one that bounces
back (``+4, +2, +1, +3``), which the unsigned depths alone cannot. Posteriors come from
the forward-backward algorithm over pairs of consecutive signs, a compiled (numba) scan
over the frames.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import gaussian_filter1d, percentile_filter

from handdb.compiled import kernel

#: Frames on each side of a frame that inform its scale.
SCALE_HALF_WINDOW = 15

#: Percentile of the per-frame scale bounds in the window taken as the scale.
SCALE_PERCENTILE = 75.0

#: Standard deviation of the Gaussian smoothing the scale, frames.
SCALE_SMOOTHING_FRAMES = 3.0

#: A term this many nats below another adds nothing to their log-sum (e^-40 < 1e-17).
NEGLIGIBLE_NATS = 40.0

#: Posterior log-odds are clipped to this magnitude (a probability of 1 − 1e-13).
MAX_LOG_ODDS = 30.0

#: What an infinite value counts as, as ``np.nan_to_num`` has it.
LARGEST_FLOAT = float(np.finfo(np.float64).max)


def acceleration_spread(values: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """Spread of each chain's second frame-to-frame difference, as the values are oriented.

    Parameters
    ----------
    values
        ``(T, K, D) float64``: each chain's value under one sign throughout; NaN: none.
    floor
        ``(K,) float64``: smallest spread, same units, added in quadrature.

    Returns
    -------
    numpy.ndarray
        ``(K,) float64``: root mean square of the second differences per component. Taken
        without sign flips, it errs large (a flip makes one large difference), so the
        prior it sets is on the weak side.
    """
    v = np.nan_to_num(values)
    squared = np.mean(np.diff(v, 2, axis=0) ** 2, axis=(0, 2)) if len(v) > 2 else 0.0
    return np.sqrt(squared + floor**2)


def sign_posterior(log_odds: np.ndarray, values: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """Posterior log-odds of each chain's positive sign, given every frame.

    Parameters
    ----------
    log_odds
        ``(T, K) float64``: each frame's own evidence for the positive sign.
    values
        ``(T, K, 2, D) float64``: each chain's value under its positive and its negative
        sign (orthographically one is minus the other; through a pinhole the near and far
        solutions differ); NaN: no value.
    spread
        ``(K,) float64``: standard deviation of each component's second frame-to-frame
        difference (:func:`acceleration_spread`).

    Returns
    -------
    numpy.ndarray
        ``(T, K) float64``, clipped to ``±MAX_LOG_ODDS``.
    """
    posterior = np.empty(log_odds.shape)
    _forward_backward(log_odds, values, 0.5 / spread**2, posterior)
    return posterior


@kernel
def _log_add_exp(a: float, b: float) -> float:
    """``log(e^a + e^b)``; the larger alone when the other adds less than ``e^-NEGLIGIBLE``."""
    high, low = max(a, b), min(a, b)
    if low - high < -NEGLIGIBLE_NATS:
        return high
    return high + math.log1p(math.exp(low - high))


@kernel
def _finite(x: float) -> float:
    """``np.nan_to_num`` of one value: NaN to 0, infinities to the largest finite floats."""
    if math.isnan(x):
        return 0.0
    if math.isinf(x):
        return LARGEST_FLOAT if x > 0 else -LARGEST_FLOAT
    return x


@kernel
def _clipped(x: float) -> float:
    """``x`` within ``±MAX_LOG_ODDS``; NaN stays NaN."""
    if math.isnan(x):
        return x
    return min(max(x, -MAX_LOG_ODDS), MAX_LOG_ODDS)


@kernel
def _acceleration_costs(values, weight, cost):
    """Fill ``cost[t, a, b, c]``, nats, of signs ``a, b, c`` (0: +, 1: −) at ``t − 2, t − 1, t``.

    ``values`` is ``(T, 2, D)``: the chain's value under each sign.
    """
    n_frames, _, n_components = values.shape
    for t in range(2, n_frames):
        for a in range(2):
            for b in range(2):
                for c in range(2):
                    total = 0.0
                    for d in range(n_components):
                        x = (values[t, c, d] - 2.0 * values[t - 1, b, d]
                             + values[t - 2, a, d])
                        total += x * x
                    cost[t, a, b, c] = weight * total


@kernel
def _forward_backward(evidence, values, weight, posterior):
    """Fill ``posterior`` ``(T, K)`` as :func:`sign_posterior` returns it.

    The chain's states are pairs of consecutive signs: ``forward[t, a, b]`` and
    ``backward[t, a, b]`` are the log-messages of signs ``a`` at ``t − 1`` and ``b`` at
    ``t`` (0: +, 1: −); ``emission[t, a]`` is frame ``t``'s own evidence for sign ``a``.
    NaN in ``evidence`` ``(T, K)`` and ``values`` ``(T, K, 2, D)`` counts as 0.
    """
    n_frames, n_chains = evidence.shape
    if n_frames == 1:
        for k in range(n_chains):
            posterior[0, k] = _clipped(_finite(evidence[0, k]))
        return
    cost = np.zeros((n_frames, 2, 2, 2))
    chain = np.empty(values.shape[:1] + values.shape[2:])
    emission = np.empty((n_frames, 2))
    forward = np.empty((n_frames, 2, 2))
    backward = np.zeros((n_frames, 2, 2))
    for k in range(n_chains):
        for t in range(n_frames):
            for sign in range(2):
                for d in range(chain.shape[2]):
                    chain[t, sign, d] = _finite(values[t, k, sign, d])
        _acceleration_costs(chain, weight[k], cost)
        for t in range(n_frames):
            # One frame is never surer than MAX_LOG_ODDS: unbounded evidence would let two
            # certain frames that disagree make every path impossible.
            own = _clipped(_finite(evidence[t, k]))
            emission[t, 0], emission[t, 1] = 0.5 * own, -0.5 * own
        for a in range(2):
            for b in range(2):
                forward[1, a, b] = emission[0, a] + emission[1, b]
        for t in range(2, n_frames):
            for b in range(2):
                for c in range(2):
                    forward[t, b, c] = emission[t, c] + _log_add_exp(
                        forward[t - 1, 0, b] - cost[t, 0, b, c],
                        forward[t - 1, 1, b] - cost[t, 1, b, c])
        for t in range(n_frames - 2, 0, -1):
            for a in range(2):
                for b in range(2):
                    backward[t, a, b] = _log_add_exp(
                        emission[t + 1, 0] - cost[t + 1, a, b, 0] + backward[t + 1, b, 0],
                        emission[t + 1, 1] - cost[t + 1, a, b, 1] + backward[t + 1, b, 1])
        for t in range(1, n_frames):
            posterior[t, k] = _clipped(
                _log_add_exp(forward[t, 0, 0] + backward[t, 0, 0],
                             forward[t, 1, 0] + backward[t, 1, 0])
                - _log_add_exp(forward[t, 0, 1] + backward[t, 0, 1],
                               forward[t, 1, 1] + backward[t, 1, 1]))
        posterior[0, k] = _clipped(
            _log_add_exp(forward[1, 0, 0] + backward[1, 0, 0],
                         forward[1, 0, 1] + backward[1, 0, 1])
            - _log_add_exp(forward[1, 1, 0] + backward[1, 1, 0],
                           forward[1, 1, 1] + backward[1, 1, 1]))


def smooth_scale(bounds: np.ndarray, percentile: float = SCALE_PERCENTILE,
                 half_window: int = SCALE_HALF_WINDOW,
                 smoothing: float = SCALE_SMOOTHING_FRAMES) -> np.ndarray:
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
    smoothing
        Standard deviation of the Gaussian smoothing that follows, frames.

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
    return gaussian_filter1d(upper, smoothing, mode="nearest")


def sigmoid(x: np.ndarray | float) -> np.ndarray:
    """Logistic function, numerically safe for large ``|x|``."""
    return 0.5 * (1.0 + np.tanh(0.5 * x))
