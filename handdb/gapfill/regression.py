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
The regressions of many gaps are fitted at once: each gap's training frames and predictors
are masks over a padded window, and the stacked normal equations are solved together.
"""

from __future__ import annotations

from dataclasses import dataclass

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
#: Gaps whose regressions are stacked in one batch (bounds the memory of the samples).
BATCH_GAPS = 64


@dataclass(frozen=True)
class _Samples:
    """The coordinates the regressions read, shared by every gap of a clip.

    Attributes
    ----------
    columns
        ``(C,) int64``: the joints read (predictors and the gaps' joints).
    centre
        ``(2 C,) float64``: the observed mean of each coordinate.
    values
        ``(T + 1, 2 C + 1) float64``: the coordinates minus ``centre``, 0 where missing,
        then a column of ones (so one matrix product gives counts, sums and scatter); the
        last row, all zeros, stands for "no sample".
    missing_bits
        ``(T,) int64``: bit ``c`` set where joint ``columns[c]`` is missing.
    """

    columns: np.ndarray
    centre: np.ndarray
    values: np.ndarray
    missing_bits: np.ndarray


def _bit_sets(members: np.ndarray) -> np.ndarray:
    """``(N, C) bool -> (N,) int64``: bit ``c`` set where column ``c`` is a member (C < 63)."""
    return members @ np.left_shift(1, np.arange(members.shape[1], dtype=np.int64))


def _samples(uv: np.ndarray, missing: np.ndarray, columns: np.ndarray) -> _Samples:
    n_frames = uv.shape[0]
    seen = np.repeat(~missing[:, columns], 2, axis=1)
    coordinates = np.where(seen, uv[:, columns].reshape(n_frames, -1), 0.0)
    centre = coordinates.sum(axis=0) / np.maximum(seen.sum(axis=0), 1)
    values = np.zeros((n_frames + 1, coordinates.shape[1] + 1))
    values[:-1, :-1] = np.where(seen, coordinates - centre, 0.0)
    values[:-1, -1] = 1.0
    return _Samples(columns, centre, values, _bit_sets(missing[:, columns]))


def _training_frames(samples: _Samples, gaps: Gaps, needed: np.ndarray) -> np.ndarray:
    """Find the frames within :data:`WINDOW` of each gap where its ``needed`` columns are seen.

    ``needed`` ``(G, C) bool`` marks the columns that must be observed in a training frame.
    Returns ``(G, F) int64`` rows of ``samples.values``: each gap's training frames, first,
    then the "no sample" row ``T`` up to the width ``F`` of the widest training set.
    """
    n_frames = gaps.n_frames
    low = np.maximum(gaps.start - WINDOW, 0)
    high = np.minimum(gaps.stop + WINDOW, n_frames)
    window = low[:, None] + np.arange(np.max(high - low))
    inside = window < high[:, None]
    window = np.minimum(window, n_frames - 1)
    train = inside & ((samples.missing_bits[window] & _bit_sets(needed)[:, None]) == 0)
    rows = np.sort(np.where(train, window, n_frames), axis=1)
    return rows[:, :max(int(train.sum(axis=1).max()), 1)]


def _predict_gaps(
    samples: _Samples, gaps: Gaps, usable: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Fit each gap's ridge regression and predict its joint around and in the gap.

    Parameters
    ----------
    samples
        The clip's coordinates (:func:`_samples`).
    gaps
        ``G`` gaps, each of a joint among ``samples.columns``.
    usable
        ``(G, C) bool``: each gap's predictor joints, among ``samples.columns``.

    Returns
    -------
    predicted
        ``(G, L + 2, 2) float64``, pixels: predictions at frames ``start - 1`` to ``stop``
        of each gap (clipped into the clip; ``L`` the longest gap).
    ok
        ``(G,) bool``: the gap had a predictor and enough training frames.
    """
    target = np.searchsorted(samples.columns, gaps.joint)
    own = np.arange(samples.columns.size) == target[:, None]
    x = samples.values[_training_frames(samples, gaps, usable | own)]
    moments = np.swapaxes(x, 1, 2) @ x
    n_train = moments[:, -1, -1]
    n = np.maximum(n_train, 1.0)[:, None]
    mean = moments[:, :-1, -1] / n
    scatter = moments[:, :-1, :-1] - n[..., None] * mean[:, :, None] * mean[:, None, :]
    use = np.repeat(usable, 2, axis=1)
    spread = np.where(use, np.maximum(np.sqrt(np.maximum(
        np.diagonal(scatter, axis1=1, axis2=2), 0.0) / n), MIN_SPREAD), np.inf)
    coordinates = 2 * target[:, None] + np.arange(2)
    gram = scatter / spread[:, :, None] / spread[:, None, :]
    gram += (RIDGE * n)[..., None] * np.eye(use.shape[1])
    cross = np.take_along_axis(scatter, coordinates[:, None, :], axis=2) / spread[..., None]
    weights = np.linalg.solve(gram, cross)
    around = np.clip(gaps.start[:, None] - 1 + np.arange(np.max(gaps.length) + 2), 0,
                     gaps.n_frames - 1)
    standard = (samples.values[around, :-1] - mean[:, None]) / spread[:, None]
    offset = np.take_along_axis(mean, coordinates, axis=1) + samples.centre[coordinates]
    predicted = standard @ weights + offset[:, None]
    ok = usable.any(axis=1) & (n_train >= MIN_TRAINING_FRAMES)
    return predicted, ok


def _blend_to_edges(
    uv: np.ndarray, gaps: Gaps, predicted: np.ndarray, gap: np.ndarray, offset: np.ndarray
) -> np.ndarray:
    """Add to each gap's prediction its residuals at the bounding frames, blended across.

    ``predicted`` is as returned by :func:`_predict_gaps`; ``gap`` and ``offset`` ``(N,)``
    list the gaps' points (gap, frames after its start). Returns ``(N, 2)`` estimates.
    """
    rows = np.arange(len(gaps))
    before = uv[np.maximum(gaps.start - 1, 0), gaps.joint] - predicted[:, 0]
    after = (uv[np.minimum(gaps.stop, gaps.n_frames - 1), gaps.joint]
             - predicted[rows, gaps.length + 1])
    before = np.where(gaps.leading[:, None], after, before)
    after = np.where(gaps.trailing[:, None], before, after)
    share = ((offset + 1) / (gaps.length[gap] + 1))[:, None]
    return predicted[gap, offset + 1] + (1 - share) * before[gap] + share * after[gap]


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
    filled = uv.copy()
    if not len(gaps):
        return filled
    n_frames = uv.shape[0]
    missing_so_far = np.vstack([np.zeros((1, missing.shape[1]), dtype=np.int64),
                                np.cumsum(missing, axis=0)])
    seen = np.where(missing[..., None], np.nan, uv)
    low, high = np.nanmin(seen, axis=0), np.nanmax(seen, axis=0)
    margin = RANGE_MARGIN * (high - low)
    gap_joints = np.zeros_like(predictors)
    gap_joints[gaps.joint] = True
    columns = np.flatnonzero(predictors | gap_joints)
    samples = _samples(uv, missing, columns)
    for batch in np.array_split(np.arange(len(gaps)), -(-len(gaps) // BATCH_GAPS)):
        part = gaps.select(batch)
        first = missing_so_far[np.maximum(part.start - 1, 0)][:, columns]
        last = missing_so_far[np.minimum(part.stop + 1, n_frames)][:, columns]
        usable = (first == last) & predictors[columns] & (columns != part.joint[:, None])
        predicted, ok = _predict_gaps(samples, part, usable)
        gap, frame, joint = part.frames()
        estimate = np.clip(_blend_to_edges(uv, part, predicted, gap, frame - part.start[gap]),
                           (low - margin)[joint], (high + margin)[joint])
        filled[frame, joint] = np.where(ok[gap, None], estimate, np.nan)
    return filled
