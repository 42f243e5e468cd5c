"""Regression fill: predict a missing joint from the joints seen throughout its gap.

For each gap, the finger joints observed over the whole gap (and the frame either side)
are the predictors. A ridge regression from their coordinates to the missing joint's is
fitted on the frames within :data:`WINDOW` frames of the gap where all of them are seen,
and applied in the gap; the prediction's residual at the frames bounding the gap is blended
across it (see :func:`~handdb.gapfill.lowrank.blend_to_edges`). Predictions are kept within
the joint's observed range widened by :data:`RANGE_MARGIN` on each side, so a regression
asked to extrapolate far cannot throw the point across the image.

It is the low-rank idea (other joints predict the missing one) fitted per gap, without
iterations. Palm points are left out as predictors: in the palm frame they hardly move.
"""

from __future__ import annotations

import numpy as np

from handdb.gapfill.gaps import Gaps

#: Frames either side of a gap whose samples train its regression.
WINDOW = 400
#: Ridge weight, per training frame, on the standardised predictors.
RIDGE = 1e-3
#: Fewest training frames a regression needs.
MIN_TRAINING_FRAMES = 10
#: Share of the joint's observed range a prediction may exceed it by, each side.
RANGE_MARGIN = 0.25
#: Predictor spread (coordinate units) below which a predictor is not scaled up.
MIN_SPREAD = 1e-6


def _fit_predict(train_x: np.ndarray, train_y: np.ndarray, query_x: np.ndarray) -> np.ndarray:
    mean_x, mean_y = train_x.mean(axis=0), train_y.mean(axis=0)
    spread = np.maximum(train_x.std(axis=0), MIN_SPREAD)
    x = (train_x - mean_x) / spread
    gram = x.T @ x + RIDGE * len(x) * np.eye(x.shape[1])
    weights = np.linalg.solve(gram, x.T @ (train_y - mean_y))
    return ((query_x - mean_x) / spread) @ weights + mean_y


def regression_fill(
    uv: np.ndarray, missing: np.ndarray, gaps: Gaps, predictors: np.ndarray
) -> np.ndarray:
    """Fill ``gaps`` by ridge regression on the ``predictors`` joints seen throughout each.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, observed points (other gaps may be filled already).
    missing
        ``(T, J) bool``: points that are not observed.
    gaps
        Non-whole-clip gaps to fill.
    predictors
        ``(J,) bool``: joints that may serve as predictors.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``uv`` with the gaps filled, NaN where a gap had no
        predictor seen throughout it or too few training frames.
    """
    n_frames = uv.shape[0]
    missing_so_far = np.vstack([np.zeros((1, missing.shape[1]), dtype=np.int64),
                                np.cumsum(missing, axis=0)])
    seen = np.where(missing[..., None], np.nan, uv)
    low, high = np.nanmin(seen, axis=0), np.nanmax(seen, axis=0)
    margin = RANGE_MARGIN * (high - low)
    filled = uv.copy()
    for joint, start, stop in zip(gaps.joint, gaps.start, gaps.stop, strict=True):
        first, last = max(start - 1, 0), min(stop + 1, n_frames)
        usable = predictors & (missing_so_far[last] == missing_so_far[first])
        usable[joint] = False
        frames = np.arange(max(start - WINDOW, 0), min(stop + WINDOW, n_frames))
        frames = frames[~missing[frames][:, usable].any(axis=1) & ~missing[frames, joint]]
        if not usable.any() or frames.size < MIN_TRAINING_FRAMES:
            filled[start:stop, joint] = np.nan
            continue
        bounded = np.arange(first, last)
        predicted = _fit_predict(uv[frames][:, usable].reshape(frames.size, -1), uv[frames, joint],
                                 uv[bounded][:, usable].reshape(bounded.size, -1))
        residual_before = uv[start - 1, joint] - predicted[0] if start > 0 else None
        residual_after = uv[stop, joint] - predicted[-1] if stop < n_frames else None
        residual_before = residual_after if residual_before is None else residual_before
        residual_after = residual_before if residual_after is None else residual_after
        share = ((np.arange(start, stop) - (start - 1)) / (stop - start + 1))[:, None]
        inside = predicted[start - first:start - first + stop - start]
        estimate = inside + (1 - share) * residual_before + share * residual_after
        filled[start:stop, joint] = np.clip(estimate, low[joint] - margin[joint],
                                            high[joint] + margin[joint])
    return filled
