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
        ``(K,) float64``: root mean square of the second differences per component, over
        the runs of three frames that all have some value (a dropped frame, all NaN,
        says nothing of the motion). Taken without sign flips, it errs large (a flip makes one large
        difference), so the prior it sets is on the weak side.
    """
    if len(values) <= 2:
        return np.sqrt(floor**2)
    squared = np.diff(np.nan_to_num(values), 2, axis=0) ** 2
    known = ~np.isnan(values).all(axis=2)                                 # (T, K)
    spanned = known[:-2] & known[1:-1] & known[2:]
    if spanned.all():
        return np.sqrt(np.mean(squared, axis=(0, 2)) + floor**2)
    counted = np.maximum(spanned.sum(axis=0) * values.shape[2], 1)
    total = np.where(spanned[..., None], squared, 0.0).sum(axis=(0, 2))
    return np.sqrt(total / counted + floor**2)


def sign_posterior(log_odds: np.ndarray, values: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """Posterior log-odds of each chain's positive sign, given every frame.

    Parameters
    ----------
    log_odds
        ``(T, K) float64``: each frame's own evidence for the positive sign.
    values
        ``(T, K, 2, D) float64``: each chain's value under its positive and its negative
        sign (orthographically one is minus the other; through a pinhole the near and far
        solutions differ); NaN: no value. A frame with no value at all (dropped) keeps its
        own evidence, and the chain bridges it.
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
def _acceleration_costs(values, frames, weight, cost):
    """Fill ``cost[i, a, b, c]``, nats, of signs ``a, b, c`` at chain frames ``i − 2, i − 1, i``.

    Signs are 0: +, 1: −. ``values`` is ``(N, 2, D)``: the chain's value under each sign
    on the frames ``frames`` ``(N,)`` that have one. Across dropped frames the second
    difference is the change of the mean velocity over the two steps, whose variance
    under the constant-velocity prior grows with their summed length, so a gap weakens
    the tie between the frames on either side of it rather than cutting or faking it.
    """
    n_frames, _, n_components = values.shape
    for i in range(2, n_frames):
        before, after = frames[i - 1] - frames[i - 2], frames[i] - frames[i - 1]
        unit = before == 1 and after == 1
        for a in range(2):
            for b in range(2):
                for c in range(2):
                    total = 0.0
                    for d in range(n_components):
                        # Unit steps keep the plain second difference and its rounding.
                        if unit:
                            x = (values[i, c, d] - 2.0 * values[i - 1, b, d]
                                 + values[i - 2, a, d])
                        else:
                            x = ((values[i, c, d] - values[i - 1, b, d]) / after
                                 - (values[i - 1, b, d] - values[i - 2, a, d]) / before)
                        total += x * x
                    cost[i, a, b, c] = weight * total if unit else \
                        weight * total * 2.0 / (before + after)


@kernel
def _forward_backward(evidence, values, weight, posterior):
    """Fill ``posterior`` ``(T, K)`` as :func:`sign_posterior` returns it.

    Each chain runs over the frames where any of its values is known (a dropped frame,
    all NaN, keeps its own evidence alone). The chain's states are pairs of consecutive
    signs: ``forward[i, a, b]`` and ``backward[i, a, b]`` are the log-messages of signs
    ``a`` at its frame ``i − 1`` and ``b`` at ``i`` (0: +, 1: −); ``emission[i, a]`` is
    frame ``i``'s own evidence for sign ``a``. Other NaN in ``evidence`` ``(T, K)`` and
    ``values`` ``(T, K, 2, D)`` counts as 0.
    """
    n_total, n_chains = evidence.shape
    n_components = values.shape[3]
    frames = np.empty(n_total, dtype=np.int64)
    chain = np.empty((n_total, 2, n_components))
    cost = np.zeros((n_total, 2, 2, 2))
    emission = np.empty((n_total, 2))
    forward = np.empty((n_total, 2, 2))
    backward = np.zeros((n_total, 2, 2))
    for k in range(n_chains):
        n_frames = 0
        for t in range(n_total):
            # One frame is never surer than MAX_LOG_ODDS: unbounded evidence would let two
            # certain frames that disagree make every path impossible.
            posterior[t, k] = _clipped(_finite(evidence[t, k]))
            known = False
            for sign in range(2):
                for d in range(n_components):
                    known = known or not math.isnan(values[t, k, sign, d])
            if known:
                frames[n_frames] = t
                n_frames += 1
        if n_frames < 2:
            continue
        for i in range(n_frames):
            t = frames[i]
            for sign in range(2):
                for d in range(n_components):
                    chain[i, sign, d] = _finite(values[t, k, sign, d])
            own = posterior[t, k]
            emission[i, 0], emission[i, 1] = 0.5 * own, -0.5 * own
        _acceleration_costs(chain[:n_frames], frames[:n_frames], weight[k], cost)
        for a in range(2):
            for b in range(2):
                forward[1, a, b] = emission[0, a] + emission[1, b]
        for i in range(2, n_frames):
            for b in range(2):
                for c in range(2):
                    forward[i, b, c] = emission[i, c] + _log_add_exp(
                        forward[i - 1, 0, b] - cost[i, 0, b, c],
                        forward[i - 1, 1, b] - cost[i, 1, b, c])
        for a in range(2):
            for b in range(2):
                backward[n_frames - 1, a, b] = 0.0
        for i in range(n_frames - 2, 0, -1):
            for a in range(2):
                for b in range(2):
                    backward[i, a, b] = _log_add_exp(
                        emission[i + 1, 0] - cost[i + 1, a, b, 0] + backward[i + 1, b, 0],
                        emission[i + 1, 1] - cost[i + 1, a, b, 1] + backward[i + 1, b, 1])
        for i in range(1, n_frames):
            posterior[frames[i], k] = _clipped(
                _log_add_exp(forward[i, 0, 0] + backward[i, 0, 0],
                             forward[i, 1, 0] + backward[i, 1, 0])
                - _log_add_exp(forward[i, 0, 1] + backward[i, 0, 1],
                               forward[i, 1, 1] + backward[i, 1, 1]))
        posterior[frames[0], k] = _clipped(
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
        Gaussian-smoothed. Frames without a bound (NaN) inform no other frame's scale and
        take the scale of their nearest frames that have one.
    """
    finite = np.isfinite(bounds)
    if not finite.any():
        return np.full(bounds.shape, np.nan)
    if finite.all():
        upper = percentile_filter(bounds, percentile, size=2 * half_window + 1,
                                  mode="nearest")
        return gaussian_filter1d(upper, smoothing, mode="nearest")
    upper = _window_percentile(bounds, percentile, half_window)
    known = np.isfinite(upper)
    weight = gaussian_filter1d(known.astype(np.float64), smoothing, mode="nearest")
    with np.errstate(invalid="ignore", divide="ignore"):
        smoothed = gaussian_filter1d(np.where(known, upper, 0.0), smoothing,
                                     mode="nearest") / weight
    return _interpolated(np.where(known, smoothed, np.nan))


def _window_percentile(values: np.ndarray, percentile: float, half_window: int) -> np.ndarray:
    """The percentile of the finite ``values`` ``(T,)`` in a window around each frame.

    The rank is the one :func:`scipy.ndimage.percentile_filter` takes among a window's
    values, taken here among its finite ones; NaN where a window has none. The clip's
    first and last values stand beyond its ends, as ``mode="nearest"`` has it.
    """
    padded = np.pad(values, half_window, mode="edge")
    windows = np.sort(np.lib.stride_tricks.sliding_window_view(padded, 2 * half_window + 1),
                      axis=1)                                             # NaN sort last
    count = np.isfinite(windows).sum(axis=1)
    rank = np.minimum((percentile / 100.0 * count).astype(np.int64), np.maximum(count - 1, 0))
    chosen = windows[np.arange(len(values)), rank]
    return np.where(count > 0, chosen, np.nan)


def _interpolated(values: np.ndarray) -> np.ndarray:
    """``values`` ``(T,)`` with NaN entries linearly interpolated from the finite ones."""
    finite = np.isfinite(values)
    index = np.arange(len(values))
    return np.interp(index, index[finite], values[finite])


def sigmoid(x: np.ndarray | float) -> np.ndarray:
    """Logistic function, numerically safe for large ``|x|``."""
    return 0.5 * (1.0 + np.tanh(0.5 * x))
