"""Detector noise: how much a clip's tracks jitter, and the tracks smoothed in time.

A detector's points jitter by a pixel or a few from frame to frame. Gap filling estimates
a missing point from observed ones (the frames bounding a gap, the bones that carry a
finger), and lifting takes a bone's depth from the small difference of its length and its
image, so the jitter of a few points goes straight into both. Both stages therefore work
from smoothed tracks (:mod:`handdb.gapfill.auto`, :mod:`handdb.lifting.kinematic`); the
stored observations stay as they were.

:func:`noise_level` measures the jitter from the clip itself: the fourth difference of a
track, ``x[t-2] - 4 x[t-1] + 6 x[t] - 4 x[t+1] + x[t+2]``, is nearly blind to motion (it
vanishes on any cubic in time) and has variance ``70 sigma^2`` for independent noise of
deviation ``sigma``; its median absolute value over every run of five observed frames gives
``sigma`` robustly.

:func:`denoise` smooths each observed run of each track with a Savitzky-Golay filter
(a quadratic fitted over a window of frames, evaluated at its centre, or at the run's
ends within the first and last windows), the half-width picked from
:data:`SMOOTHING_HALF_WIDTHS`, or none, by Stein's unbiased risk estimate
(``|y - x|^2 + 2 sigma^2 tr(S) - n sigma^2`` for a linear smoother ``y = S x``): the
window that removes most noise for the least motion it blurs, on this clip. Clean tracks
(a noise level below :data:`MIN_NOISE_PX`) are left as they are.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from handdb.compiled import kernel
from handdb.robust import MAD_TO_SIGMA

#: Half-widths (frames) of the smoothing windows tried; 2 is the narrowest window (5
#: frames) in which a quadratic does not pass through every sample.
SMOOTHING_HALF_WIDTHS = (2, 3, 4, 6)
#: Degree of the polynomial fitted in each window.
SMOOTHING_DEGREE = 2
#: Noise level (pixels) below which tracks are taken as clean and not smoothed.
MIN_NOISE_PX = 0.05
#: Variance of the fourth difference of unit white noise: 1 + 16 + 36 + 16 + 1.
FOURTH_DIFFERENCE_VARIANCE = 70.0
#: Fourth differences the noise level's median is taken over, at most.
NOISE_SAMPLES = 20_000
#: Observed points Stein's risk of each window is estimated from, at most (every k-th
#: frame of each run on longer clips).
RISK_SAMPLES = 20_000


def noise_level(uv: np.ndarray, missing: np.ndarray) -> float:
    """Standard deviation of the tracks' frame-to-frame jitter, pixels.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, finite where observed.
    missing
        ``(T, J) bool``.

    Returns
    -------
    float
        Pixels per coordinate; 0 when no joint is observed in five consecutive frames. On
        long clips the median is taken over :data:`NOISE_SAMPLES` fourth differences
        evenly spread over the clip.
    """
    fourth = _fourth_differences(uv, missing)
    if fourth.size == 0:
        return 0.0
    if fourth.size > NOISE_SAMPLES:
        fourth = fourth[:: fourth.size // NOISE_SAMPLES]
    return MAD_TO_SIGMA * float(np.median(fourth)) / np.sqrt(FOURTH_DIFFERENCE_VARIANCE)


@kernel
def _fourth_differences(uv: np.ndarray, missing: np.ndarray) -> np.ndarray:
    """Absolute fourth differences of every coordinate over five observed frames, pixels.

    ``uv`` is ``(T, J, 2)``, ``missing`` ``(T, J) bool``; returns ``(N,) float64``.
    """
    n_frames, n_joints = missing.shape
    values = np.empty(2 * max(n_frames - 4, 0) * n_joints)
    count = 0
    for j in range(n_joints):
        for t in range(2, n_frames - 2):
            if (missing[t - 2, j] or missing[t - 1, j] or missing[t, j] or missing[t + 1, j]
                    or missing[t + 2, j]):
                continue
            for k in range(2):
                values[count] = abs(uv[t - 2, j, k] - 4.0 * uv[t - 1, j, k] + 6.0 * uv[t, j, k]
                                    - 4.0 * uv[t + 1, j, k] + uv[t + 2, j, k])
                count += 1
    return values[:count]


@cache
def smoothing_weights(half: int) -> np.ndarray:
    """The Savitzky-Golay weights of a window of ``2 half + 1`` frames.

    Returns
    -------
    numpy.ndarray
        ``(2 half + 1, 2 half + 1) float64``, read-only: row ``k`` weighs the window's
        samples to evaluate the fitted polynomial at its ``k``-th frame (row ``half``, the
        centre, is the ordinary filter).
    """
    offsets = np.arange(-half, half + 1, dtype=np.float64)
    vandermonde = np.vander(offsets, SMOOTHING_DEGREE + 1)
    weights = vandermonde @ np.linalg.pinv(vandermonde)
    weights.flags.writeable = False
    return weights


def denoise(uv: np.ndarray, missing: np.ndarray) -> tuple[np.ndarray, int]:
    """Smooth the observed runs of every track by the window Stein's risk picks.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, finite where observed.
    missing
        ``(T, J) bool``.

    Returns
    -------
    smoothed
        ``(T, J, 2) float64``: a copy of ``uv`` with its observed points smoothed, or
        ``uv`` itself when no window lowers the risk; missing points as they were.
    half
        The half-width chosen, frames; 0 for none.
    """
    sigma = noise_level(uv, missing)
    if sigma < MIN_NOISE_PX:
        return uv, 0
    variance = sigma * sigma
    stride = max(int(np.count_nonzero(~missing)) // RISK_SAMPLES, 1)
    best_half, best_risk = 0, 0.0
    for half in SMOOTHING_HALF_WIDTHS:
        change, trace, count = _smooth_runs(uv, missing, smoothing_weights(half), uv, stride,
                                            False)
        # Stein's risk minus that of no smoothing (n sigma^2), over both coordinates.
        risk = change + 2.0 * variance * (2.0 * trace - 2.0 * count)
        if risk < best_risk:
            best_half, best_risk = half, risk
    if best_half == 0:
        return uv, 0
    smoothed = uv.copy()
    _smooth_runs(uv, missing, smoothing_weights(best_half), smoothed, 1, True)
    return smoothed, best_half


@kernel
def _smooth_runs(uv: np.ndarray, missing: np.ndarray, weights: np.ndarray,
                 out: np.ndarray, stride: int, write: bool) -> tuple[float, float, int]:
    """Smooth every observed run at least a window long into ``out``.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    missing
        ``(T, J) bool``.
    weights
        ``(W, W) float64``: :func:`smoothing_weights` of the window.
    out, write
        ``(T, J, 2) float64``: where the smoothed points are written, if ``write`` (else
        only the risk's terms are wanted).
    stride
        The risk's terms are summed over the frames that are multiples of ``stride`` (every
        frame is written).

    Returns
    -------
    change
        Sum of the squared changes of the summed observed coordinates, pixels squared.
    trace
        The trace of the smoother over one coordinate of the summed observed points (a
        point of a run shorter than the window counts 1: it is kept).
    count
        How many observed points were summed.
    """
    n_frames, n_joints = missing.shape
    width = weights.shape[0]
    half = width // 2
    change = 0.0
    trace = 0.0
    count = 0
    for j in range(n_joints):
        t = 0
        while t < n_frames:
            if missing[t, j]:
                t += 1
                continue
            start = t
            while t < n_frames and not missing[t, j]:
                t += 1
            stop = t
            for frame in range(start, stop):
                summed = frame % stride == 0
                count += summed
                if stop - start < width:
                    trace += summed
                    continue
                if not (summed or write):
                    continue
                first = min(max(frame - half, start), stop - width)
                row = frame - first
                if summed:
                    trace += weights[row, row]
                for k in range(2):
                    value = 0.0
                    for i in range(width):
                        value += weights[row, i] * uv[first + i, j, k]
                    if summed:
                        change += (value - uv[frame, j, k]) ** 2
                    if write:
                        out[frame, j, k] = value
    return change, trace, count
