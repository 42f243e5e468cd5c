"""A clip's evidence from correlated frames: each series counted once per independent frame.

A clip-wide choice (which of a template's two chiralities, a solution or its mirror) is
judged by the per-frame log-likelihoods of its sources (each finger's anatomy, the palm's
fit, the thumb base's height) summed over the frames. Consecutive frames of a clip are not
independent draws: a finger the prior models badly in one pose favours the wrong
hypothesis for as long as the hand holds that pose, and the plain sum counts that once per
frame. Each source's summed log-likelihood ratio is therefore divided by its integrated
autocorrelation time, the number of frames that carry as much as one independent frame
(Geyer's initial positive sequence estimator; Geyer 1992, *Practical Markov chain Monte
Carlo*, Statistical Science 7(4)), which puts the clip's log-odds on the scale of
independent evidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def autocorrelation_time(series: np.ndarray) -> np.ndarray:
    """Integrated autocorrelation time of each series, frames.

    Parameters
    ----------
    series
        ``(T, S) float64``: ``S`` series over ``T`` frames, finite.

    Returns
    -------
    numpy.ndarray
        ``(S,) float64`` in ``[1, T]``: ``1 + 2 sum_k rho_k`` over the initial positive
        sequence of the autocorrelations ``rho_k`` paired as ``rho_2m + rho_2m+1``; 1 for
        a constant series, a single frame or none (nothing says the frames are alike).
    """
    n_frames, n_series = series.shape
    if n_frames < 2:
        return np.ones(n_series)
    centred = series - series.mean(axis=0)
    size = 2 ** int(np.ceil(np.log2(2 * n_frames)))
    spectrum = np.fft.rfft(centred, n=size, axis=0)
    covariance = np.fft.irfft(spectrum * np.conj(spectrum), n=size, axis=0)[:n_frames]
    tau = np.ones(n_series)
    for s in np.flatnonzero(covariance[0] > 0):
        rho = covariance[:, s] / covariance[0, s]
        pairs = rho[: n_frames - n_frames % 2].reshape(-1, 2).sum(axis=1)
        stop = np.flatnonzero(pairs <= 0)
        kept = pairs[: stop[0] if stop.size else len(pairs)]
        tau[s] = 2.0 * kept.sum() - 1.0
    return np.clip(tau, 1.0, n_frames)


@dataclass(frozen=True)
class Evidence:
    """Log-likelihood of a clip's solution, or a log-ratio of two, by source.

    Attributes
    ----------
    frames
        ``(T, S) float64``, nats: each source's term in each frame.
    clip
        Nats: the terms of the clip as a whole (a shape, a prior on a clip-wide value).
    """

    frames: np.ndarray
    clip: float

    def total(self) -> float:
        """Every term summed, frames counted as independent, nats."""
        return float(self.frames.sum()) + self.clip

    def calibrated(self) -> float:
        """Every source's sum over its independent frames (:func:`autocorrelation_time`).

        Meaningful for a log-ratio of two solutions: the log-odds of the first, nats.
        """
        return float((self.frames.sum(axis=0) / autocorrelation_time(self.frames)).sum()
                     + self.clip)

    def __neg__(self) -> Evidence:
        """The log-ratio the other way round."""
        return Evidence(-self.frames, -self.clip)

    def __sub__(self, other: Evidence) -> Evidence:
        """The log-ratio of this solution against ``other`` (same frames and sources)."""
        return Evidence(self.frames - other.frames, self.clip - other.clip)
