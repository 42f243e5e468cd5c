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

The regressions of many gaps are fitted at once. The clip's coordinates are gathered once
(:func:`regression_samples`) with a column of ones, so a gap's counts, sums and scatter are
the sum of the outer products of its training rows. The frames where every joint is seen
are summed by blocks of :data:`BLOCK` frames in running sums, so a gap's window costs two
look-ups for its whole blocks, and only its other training frames (and, with a sign, the
frames another problem hides, such as the validation's hidden runs) are gathered. Gaps of
similar list lengths are stacked in batches and their normal equations solved together.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from handdb.compiled import kernel
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
#: Bytes of training rows gathered at a time. A whole batch at once takes megabytes that
#: the allocator hands back to the system and faults in again on every fill (on 400
#: frames, some 400 page faults, about a quarter of the fill's time).
PART_BYTES = 1 << 18
#: Frames per block of the running moment sums over the frames every regression trains on.
BLOCK = 32


@dataclass(frozen=True)
class Samples:
    """The coordinates the regressions of a clip read, shared by every gap.

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
    complete
        ``(T,) bool``: the frames where every column is observed.
    running
        ``(T // BLOCK + 1, 2 C + 1, 2 C + 1) float64``: running sums of the moments of the
        complete frames, by blocks (:func:`_block_moments`).
    """

    columns: np.ndarray
    centre: np.ndarray
    values: np.ndarray
    complete: np.ndarray
    running: np.ndarray

    def coordinates(self, frame: np.ndarray, column: np.ndarray) -> np.ndarray:
        """``(N, 2) float64``, pixels: the observed points of ``column`` at ``frame``."""
        pair = 2 * column[:, None] + np.arange(2)
        return self.values[frame[:, None], pair] + self.centre[pair]


def _bit_sets(members: np.ndarray) -> np.ndarray:
    """``(N, C) bool -> (N,) int64``: bit ``c`` set where column ``c`` is a member (C < 63)."""
    return members @ np.left_shift(1, np.arange(members.shape[1], dtype=np.int64))


def regression_samples(uv: np.ndarray, missing: np.ndarray, columns: np.ndarray) -> Samples:
    """Gather the coordinates of the joints ``columns`` that the regressions read.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, finite at the observed points.
    missing
        ``(T, J) bool``: points that are not observed (their values are never read).
    columns
        ``(C,) int64``, ascending: the joints to read.

    Returns
    -------
    Samples
        Valid for regressions whose missing points include ``missing``: a regression that
        hides more points only reads samples where they are seen.
    """
    n_frames = uv.shape[0]
    seen = ~missing[:, columns]
    seen_coordinates = np.repeat(seen, 2, axis=1)
    coordinates = np.where(seen_coordinates,
                           np.take(uv, columns, axis=1).reshape(n_frames, -1), 0.0)
    centre = coordinates.sum(axis=0) / np.maximum(seen_coordinates.sum(axis=0), 1)
    values = np.zeros((n_frames + 1, coordinates.shape[1] + 1))
    np.subtract(coordinates, centre, out=values[:-1, :-1], where=seen_coordinates)
    values[:-1, -1] = 1.0
    complete = np.asarray(seen.all(axis=1), dtype=bool)
    return Samples(columns, centre, values, complete, _block_moments(values, complete))


def _block_moments(values: np.ndarray, complete: np.ndarray) -> np.ndarray:
    """Running sums of the moments of the ``complete`` frames, at every :data:`BLOCK` frames.

    Parameters
    ----------
    values
        ``(T + 1, D) float64``: ``Samples.values``.
    complete
        ``(T,) bool``: frames to sum.

    Returns
    -------
    numpy.ndarray
        ``(T // BLOCK + 1, D, D) float64``: entry ``b`` sums the outer products of the rows
        of the complete frames before frame ``b * BLOCK``.
    """
    n_blocks = complete.size // BLOCK
    framed = n_blocks * BLOCK
    x = np.where(complete[:framed, None], values[:framed], 0.0).reshape(n_blocks, BLOCK,
                                                                       values.shape[1])
    running = np.zeros((n_blocks + 1, x.shape[2], x.shape[2]))
    # A copy of the transposed blocks: numpy multiplies a view of x by x itself slower.
    np.cumsum(np.ascontiguousarray(np.swapaxes(x, 1, 2)) @ x, axis=0, out=running[1:])
    return running


@dataclass(frozen=True)
class _Training:
    """The frames each gap's regression trains on.

    The frames of the window's whole blocks where every column is observed are summed from
    the samples' running sums; the training frames outside them are listed with sign +1,
    and the summed frames that are not training frames (points a problem hides beyond the
    samples' own) with sign -1.

    Attributes
    ----------
    rows
        ``(G, F) int64`` rows of ``Samples.values``: each gap's listed frames, first, then
        the "no sample" row ``T`` up to the width ``F`` of the longest list.
    signs
        ``(G, F) float64``: +1 or -1 for each listed frame, 0 for padding.
    n_rows
        ``(G,) int64``: listed frames of each gap.
    n_train
        ``(G,) int64``: training frames of each gap.
    blocks
        ``(G, 2) int64``: the first and one past the last block summed for each gap.
    """

    rows: np.ndarray
    signs: np.ndarray
    n_rows: np.ndarray
    n_train: np.ndarray
    blocks: np.ndarray


def _training_frames(
    missing_bits: np.ndarray, problem: np.ndarray, gaps: Gaps, needed: np.ndarray,
    complete: np.ndarray,
) -> _Training:
    """Find the frames within :data:`WINDOW` of each gap where its ``needed`` columns are seen.

    Parameters
    ----------
    missing_bits
        ``(P, T) int64``: for each problem, bit ``c`` set where column ``c`` is missing.
    problem
        ``(G,) int64``: the problem of each gap.
    gaps
        The gaps.
    needed
        ``(G, C) bool``: the columns that must be observed in a training frame.
    complete
        ``(T,) bool``: the frames the block sums cover where they cover a block.
    """
    return _Training(*_list_training_frames(missing_bits, problem, gaps.start, gaps.stop,
                                            _bit_sets(needed), complete))


@kernel
def _list_training_frames(
    missing_bits: np.ndarray, problem: np.ndarray, start: np.ndarray, stop: np.ndarray,
    needed_bits: np.ndarray, complete: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The fields of :class:`_Training` (see :func:`_training_frames`).

    Parameters
    ----------
    missing_bits, problem, complete
        As for :func:`_training_frames`.
    start, stop
        ``(G,) int64``: the gaps' frames.
    needed_bits
        ``(G,) int64``: bit ``c`` set where column ``c`` must be observed to train.

    Returns
    -------
    rows, signs, n_rows, n_train, blocks
        As in :class:`_Training`.
    """
    n_gaps, n_frames = start.size, complete.size
    low, high = np.maximum(start - WINDOW, 0), np.minimum(stop + WINDOW, n_frames)
    rows = np.full((n_gaps, max(np.max(high - low), 1)), n_frames)
    signs = np.zeros(rows.shape)
    n_rows, n_train = np.zeros(n_gaps, dtype=np.int64), np.zeros(n_gaps, dtype=np.int64)
    blocks = np.empty((n_gaps, 2), dtype=np.int64)
    for g in range(n_gaps):
        first_block = -(-low[g] // BLOCK)
        blocks[g, 0], blocks[g, 1] = first_block, max(high[g] // BLOCK, first_block)
        for frame in range(low[g], high[g]):
            train = (missing_bits[problem[g], frame] & needed_bits[g]) == 0
            summed = (complete[frame] and frame >= BLOCK * blocks[g, 0]
                      and frame < BLOCK * blocks[g, 1])
            n_train[g] += train
            if train != summed:
                rows[g, n_rows[g]] = frame
                signs[g, n_rows[g]] = 1.0 if train else -1.0
                n_rows[g] += 1
    width = max(np.max(n_rows), 1)
    return (np.ascontiguousarray(rows[:, :width]), np.ascontiguousarray(signs[:, :width]),
            n_rows, n_train, blocks)


def _predict_gaps(
    samples: Samples, moments: np.ndarray, gaps: Gaps, usable: np.ndarray, span: int
) -> np.ndarray:
    """Fit each gap's ridge regression and predict its joint around and in the gap.

    Parameters
    ----------
    samples
        The clip's coordinates (:func:`regression_samples`).
    moments
        ``(G, D, D) float64``: each gap's sum of the outer products of its training rows
        of ``samples.values`` (``D = 2 C + 1``).
    gaps
        ``G`` gaps, each of a joint among ``samples.columns``.
    usable
        ``(G, C) bool``: each gap's predictor joints, among ``samples.columns``.
    span
        Frames predicted per gap, at least its length plus 2.

    Returns
    -------
    numpy.ndarray
        ``(G, span, 2) float64``, pixels: predictions at frames ``start - 1`` onward of
        each gap (clipped into the clip).
    """
    target = np.searchsorted(samples.columns, gaps.joint)
    coordinates = 2 * target[:, None] + np.arange(2)
    mean, spread, gram, cross = _normal_equations(moments, usable, coordinates)
    standard_weights = np.linalg.solve(gram, cross)
    # On the rows of samples.values (the centred coordinates, then 1): the standardised
    # predictors' weights, and the constant that restores the target's mean.
    weights = np.empty((len(gaps), moments.shape[1], 2))
    weights[:, :-1] = standard_weights / spread[..., None]
    weights[:, -1] = (np.take_along_axis(mean, coordinates, axis=1) + samples.centre[coordinates]
                      - (mean[:, None] @ weights[:, :-1])[:, 0])
    around = np.clip(gaps.start[:, None] - 1 + np.arange(span), 0, gaps.n_frames - 1)
    return samples.values[around] @ weights


@kernel
def _normal_equations(
    moments: np.ndarray, usable: np.ndarray, coordinates: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each gap's ridge regression on standardised predictors, as normal equations.

    Parameters
    ----------
    moments
        ``(G, D, D) float64``: as for :func:`_predict_gaps` (``D = 2 C + 1``).
    usable
        ``(G, C) bool``: each gap's predictor joints.
    coordinates
        ``(G, 2) int64``: the target's two coordinates among the ``2 C``.

    Returns
    -------
    mean
        ``(G, 2 C) float64``: the training frames' mean of each coordinate (centred).
    spread
        ``(G, 2 C) float64``: each predictor's standard deviation (at least
        :data:`MIN_SPREAD`), ``inf`` for a coordinate that is not a predictor.
    gram, cross
        ``(G, 2 C, 2 C)`` and ``(G, 2 C, 2) float64``: the standardised predictors' scatter
        plus :data:`RIDGE` per training frame on the diagonal, and their scatter with the
        target.
    """
    n_gaps, size = moments.shape[0], moments.shape[1] - 1
    mean, spread = np.empty((n_gaps, size)), np.empty((n_gaps, size))
    gram, cross = np.empty((n_gaps, size, size)), np.empty((n_gaps, size, 2))
    scatter = np.empty((size, size))
    for g in range(n_gaps):
        n = max(moments[g, -1, -1], 1.0)
        for i in range(size):
            mean[g, i] = moments[g, i, -1] / n
        for i in range(size):
            for j in range(size):
                scatter[i, j] = moments[g, i, j] - n * mean[g, i] * mean[g, j]
        for i in range(size):
            spread[g, i] = (max(np.sqrt(max(scatter[i, i], 0.0) / n), MIN_SPREAD)
                            if usable[g, i // 2] else np.inf)
        for i in range(size):
            for j in range(size):
                gram[g, i, j] = (scatter[i, j] / spread[g, i] / spread[g, j]
                                 + RIDGE * n * (1.0 if i == j else 0.0))
            for k in range(2):
                cross[g, i, k] = scatter[i, coordinates[g, k]] / spread[g, i]
    return mean, spread, gram, cross


def _blend_to_edges(
    samples: Samples, gaps: Gaps, predicted: np.ndarray, gap: np.ndarray, offset: np.ndarray
) -> np.ndarray:
    """Add to each gap's prediction its residuals at the bounding frames, blended across.

    ``predicted`` is as returned by :func:`_predict_gaps`; ``gap`` and ``offset`` ``(N,)``
    list the gaps' points (gap, frames after its start). Returns ``(N, 2)`` estimates.
    """
    rows = np.arange(len(gaps))
    column = np.searchsorted(samples.columns, gaps.joint)
    before = (samples.coordinates(np.maximum(gaps.start - 1, 0), column)
              - predicted[:, 0])
    after = (samples.coordinates(np.minimum(gaps.stop, gaps.n_frames - 1), column)
             - predicted[rows, gaps.length + 1])
    before = np.where(gaps.leading[:, None], after, before)
    after = np.where(gaps.trailing[:, None], before, after)
    share = ((offset + 1) / (gaps.length[gap] + 1))[:, None]
    return predicted[gap, offset + 1] + (1 - share) * before[gap] + share * after[gap]


@kernel
def _read_problem(
    missing: np.ndarray, columns: np.ndarray, predictors: np.ndarray, joint: np.ndarray,
    start: np.ndarray, stop: np.ndarray, values: np.ndarray, centre: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What the regressions of one problem need to know of its missing points.

    Parameters
    ----------
    missing
        ``(T, J) bool``: the problem's missing points.
    columns
        ``(C,) int64``: the joints the samples read (``Samples.columns``).
    predictors
        ``(J,) bool``: joints that may serve as predictors.
    joint, start, stop
        ``(G,) int64``: the problem's gaps.
    values, centre
        ``Samples.values`` and ``Samples.centre``.

    Returns
    -------
    usable
        ``(G, C) bool``: each gap's predictors, seen throughout the gap and the frame either
        side.
    missing_bits
        ``(T,) int64``: bit ``c`` set where column ``c`` is missing.
    low, high
        ``(2 C,) float64``, pixels: the lowest and highest value of each coordinate where
        seen (``inf`` and ``-inf`` where never).
    """
    n_frames, n_columns = missing.shape[0], columns.size
    missing_so_far = np.zeros((n_frames + 1, n_columns), dtype=np.int64)
    missing_bits = np.zeros(n_frames, dtype=np.int64)
    low, high = np.full(2 * n_columns, np.inf), np.full(2 * n_columns, -np.inf)
    for frame in range(n_frames):
        for c in range(n_columns):
            gone = missing[frame, columns[c]]
            missing_so_far[frame + 1, c] = missing_so_far[frame, c] + gone
            if gone:
                missing_bits[frame] |= 1 << c
            else:
                for k in range(2 * c, 2 * c + 2):
                    low[k] = min(low[k], values[frame, k])
                    high[k] = max(high[k], values[frame, k])
    usable = np.empty((joint.size, n_columns), dtype=np.bool_)
    for g in range(joint.size):
        first, last = max(start[g] - 1, 0), min(stop[g] + 1, n_frames)
        for c in range(n_columns):
            usable[g, c] = (missing_so_far[last, c] == missing_so_far[first, c]
                            and predictors[columns[c]] and columns[c] != joint[g])
    return usable, missing_bits, low + centre, high + centre


def regression_estimates(
    samples: Samples, predictors: np.ndarray, problems: Sequence[tuple[np.ndarray, Gaps]]
) -> list[np.ndarray]:
    """Estimate the points of gaps by ridge regression on the predictors seen throughout.

    Several problems, each a set of gaps with the points that are missing around them, are
    solved in shared batches (gaps of similar training-set sizes together).

    Parameters
    ----------
    samples
        The clip's coordinates (:func:`regression_samples`), reading the gaps' joints and
        the ``predictors``; gathered with no more points missing than any problem has.
    predictors
        ``(J,) bool``: joints that may serve as predictors.
    problems
        ``(missing, gaps)`` pairs: ``(T, J) bool`` points that are not observed (neither
        predictors nor training samples are taken from them), and the non-whole-clip gaps
        to estimate, of joints among ``samples.columns``.

    Returns
    -------
    list of numpy.ndarray
        Per problem, ``(N, 2) float64``, pixels: the estimates at the points of
        ``gaps.frames()``, in order; NaN where a gap had no predictor seen throughout it or
        too few training frames.
    """
    if not any(len(part) for _, part in problems):
        return [np.empty((0, 2)) for _ in problems]
    columns = samples.columns
    n_frames = samples.values.shape[0] - 1
    joints, starts, stops = (np.concatenate([getattr(part, name) for _, part in problems])
                             for name in ("joint", "start", "stop"))
    gaps = Gaps(joints, starts, stops, n_frames)
    problem = np.repeat(np.arange(len(problems)), [len(part) for _, part in problems])
    missing_bits = np.empty((len(problems), n_frames), dtype=np.int64)
    low = np.empty((len(problems), 2 * columns.size))
    high = np.empty_like(low)
    usable = np.empty((len(gaps), columns.size), dtype=bool)
    for index, (missing, part) in enumerate(problems):
        usable[problem == index], missing_bits[index], low[index], high[index] = _read_problem(
            missing, columns, predictors, part.joint, part.start, part.stop, samples.values,
            samples.centre)
    own = np.arange(columns.size) == np.searchsorted(columns, gaps.joint)[:, None]
    training = _training_frames(missing_bits, problem, gaps, usable | own, samples.complete)
    span = int(np.max(gaps.length, initial=0)) + 2
    predicted = np.empty((len(gaps), span, 2))
    by_size = np.argsort(training.n_rows, kind="stable")
    for batch in np.array_split(by_size, -(-len(gaps) // BATCH_GAPS)):
        width = max(int(training.n_rows[batch].max()), 1)
        products = np.empty((batch.size, *samples.running.shape[1:]))
        per_part = max(PART_BYTES // (8 * width * products.shape[-1]), 1)
        for head in range(0, batch.size, per_part):
            listed = np.s_[batch[head:head + per_part], :width]
            x = samples.values[training.rows[listed]]
            products[head:head + per_part] = (
                np.swapaxes(x * training.signs[listed][..., None], 1, 2) @ x)
        first, last = training.blocks[batch].T
        moments = products + samples.running[last] - samples.running[first]
        predicted[batch] = _predict_gaps(samples, moments, gaps.select(batch), usable[batch],
                                         span)
    ok = usable.any(axis=1) & (training.n_train >= MIN_TRAINING_FRAMES)
    gap, frame, joint = gaps.frames()
    coordinate = (problem[gap][:, None], 2 * np.searchsorted(columns, joint)[:, None]
                  + np.arange(2))
    margin = RANGE_MARGIN * (high - low)[coordinate]
    estimate = np.clip(_blend_to_edges(samples, gaps, predicted, gap, frame - gaps.start[gap]),
                       low[coordinate] - margin, high[coordinate] + margin)
    estimate = np.where(ok[gap, None], estimate, np.nan)
    return np.split(estimate, np.cumsum([part.length.sum() for _, part in problems])[:-1])


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
    if len(gaps):
        gap_joints = np.zeros_like(predictors)
        gap_joints[gaps.joint] = True
        samples = regression_samples(uv, missing, np.flatnonzero(predictors | gap_joints))
        _, frame, joint = gaps.frames()
        filled[frame, joint] = regression_estimates(samples, predictors, [(missing, gaps)])[0]
    return filled
