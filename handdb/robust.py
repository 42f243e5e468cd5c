"""Robust statistics the stages share: a spread from the median absolute deviation."""

from __future__ import annotations

import numpy as np

#: Standard deviations per median absolute deviation, for normal samples.
MAD_TO_SIGMA = 1.4826

#: Standard error of a sample median per standard error of a sample mean, for normal
#: samples: ``sqrt(pi / 2)``.
MEDIAN_EFFICIENCY = float(np.sqrt(np.pi / 2.0))


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
    with np.errstate(all="ignore"):
        median = np.nanmedian(values, axis=axis, keepdims=True)
        return MAD_TO_SIGMA * np.nanmedian(np.abs(values - median), axis=axis)
