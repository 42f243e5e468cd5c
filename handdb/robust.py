"""Robust statistics the stages share: medians of samples with gaps, and spreads."""

from __future__ import annotations

import warnings

import numpy as np

#: Standard deviations per median absolute deviation, for normal samples.
MAD_TO_SIGMA = 1.4826

#: Standard error of a sample median per standard error of a sample mean, for normal
#: samples: ``sqrt(pi / 2)``.
MEDIAN_EFFICIENCY = float(np.sqrt(np.pi / 2.0))


def nan_median(values: np.ndarray, axis: int = 0, keepdims: bool = False) -> np.ndarray:
    """Median along ``axis`` ignoring NaN; NaN, without a warning, where no sample is finite.

    The values of ``numpy.nanmedian`` (the mean of the two middle ranks of the finite
    samples, each rank taken once when their count is odd), from one sort along ``axis``
    (NaN sorts last) instead of its masked-array median, which is much slower on a clip's
    few hundred frames.

    Parameters
    ----------
    values
        Samples along ``axis``, NaN where missing.
    axis
        The axis of the samples.
    keepdims
        Keep ``axis`` with length 1.

    Returns
    -------
    numpy.ndarray
        ``values``'s shape without ``axis`` (with it of length 1 if ``keepdims``), in its
        unit and dtype; a scalar for samples in one dimension.
    """
    values = np.asarray(values)
    if values.shape[axis] == 0:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return np.nanmedian(values, axis=axis, keepdims=keepdims)
    ordered = np.sort(values, axis=axis)
    counts = np.sum(~np.isnan(values), axis=axis, keepdims=True)
    low = np.take_along_axis(ordered, np.maximum(counts - 1, 0) // 2, axis=axis)
    high = np.take_along_axis(ordered, counts // 2, axis=axis)
    median = (low + high) / 2.0
    if not keepdims:
        median = np.squeeze(median, axis=axis)
    return median[()] if median.ndim == 0 else median


def robust_spread(values: np.ndarray, axis: int = 0) -> np.ndarray:
    """Standard deviation estimated as ``MAD_TO_SIGMA`` times the median absolute deviation.

    Parameters
    ----------
    values
        Samples along ``axis``, NaN where missing (ignored).
    axis
        The axis of the samples.

    Returns
    -------
    numpy.ndarray
        ``values``'s shape without ``axis``, in its unit; NaN where no sample is finite.
    """
    deviations = np.abs(values - nan_median(values, axis=axis, keepdims=True))
    return MAD_TO_SIGMA * nan_median(deviations, axis=axis)
