"""Carry a point from one 2D configuration of the hand to another (batched point-set fits).

A set of points that moves rigidly in 3D, seen through an orthographic camera, moves by a
2D affine map in the image; the palm is nearly such a set. :func:`map_points` fits, for
many pairs of configurations at once, the map from a *source* set of points to a *target*
set (weighted least squares over the points present in both) and applies it to a query
point. It fits an affine map where at least three points are present and well spread, a
similarity (rotation, scale, translation; closed form) where two are,
and a translation where one is.
"""

from __future__ import annotations

import numpy as np

from handdb.compiled import kernel

#: Smallest ratio of the two principal spreads of the source points accepted for an
#: affine fit (below it the points are nearly collinear and the similarity is used).
MIN_AFFINE_SPREAD = 0.05

#: Kinds of map :func:`fit_maps` fits, by the number of parameters it could determine.
NO_MAP, TRANSLATION, SIMILARITY, AFFINE = 0, 1, 2, 3


def apply_linear(linear: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply ``(N, 2, 2)`` linear maps to ``(N, 2)`` or ``(N, K, 2)`` points, one map each."""
    if points.ndim == 2:
        return np.einsum("nij,nj->ni", linear, points)
    return np.matmul(points, np.ascontiguousarray(np.swapaxes(linear, 1, 2)))


def apply_affine(linear: np.ndarray, offset: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply ``(N, 2, 2)`` linear maps and ``(N, 2)`` offsets to ``(N, K, 2)`` points."""
    mapped = apply_linear(linear, points)
    flat = mapped.reshape(len(mapped), -1)
    flat += np.tile(offset, points.shape[1])
    return mapped


def inverse_2x2(matrices: np.ndarray) -> np.ndarray:
    """Invert ``(N, 2, 2)`` matrices in closed form (no check: singular ones give inf/NaN)."""
    (a, b), (c, d) = np.moveaxis(matrices, (-2, -1), (0, 1))
    det = a * d - b * c
    return np.stack([d / det, -b / det, -c / det, a / det], axis=-1).reshape(matrices.shape)


def _member_bits(members: np.ndarray) -> np.ndarray:
    """``(N, K) bool -> (N,) int64``: bit ``k`` set where point ``k`` is a member (K < 63)."""
    return members @ np.left_shift(1, np.arange(members.shape[1], dtype=np.int64))


@kernel
def fit_map(
    source: np.ndarray, target: np.ndarray, weights: np.ndarray, affine: bool
) -> tuple[tuple[float, float, float, float, float, float], int]:
    """Fit one source-to-target map (compiled; :func:`fit_maps` fits many).

    Parameters
    ----------
    source, target
        ``(K, 2) float64``, pixels; a NaN coordinate of a point taking part counts as 0.
    weights
        ``(K,) bool``: the points that take part.
    affine
        Fit an affine map where the points allow.

    Returns
    -------
    map
        The linear part row by row, then the offset: ``(a, b, c, d, x, y)``; the offset is
        NaN where no point took part.
    kind
        :data:`AFFINE`, :data:`SIMILARITY`, :data:`TRANSLATION` or :data:`NO_MAP`.
    """
    count = 0
    sx_mean = sy_mean = dx_mean = dy_mean = 0.0
    for k in range(weights.size):
        if weights[k]:
            count += 1
            sx_mean += _finite_or_zero(source[k, 0])
            sy_mean += _finite_or_zero(source[k, 1])
            dx_mean += _finite_or_zero(target[k, 0])
            dy_mean += _finite_or_zero(target[k, 1])
    divisor = max(count, 1)
    sx_mean, sy_mean = sx_mean / divisor, sy_mean / divisor
    dx_mean, dy_mean = dx_mean / divisor, dy_mean / divisor
    sxx = sxy = syy = cxx = cxy = cyx = cyy = 0.0
    for k in range(weights.size):
        if weights[k]:
            sx = _finite_or_zero(source[k, 0]) - sx_mean
            sy = _finite_or_zero(source[k, 1]) - sy_mean
            dx = _finite_or_zero(target[k, 0]) - dx_mean
            dy = _finite_or_zero(target[k, 1]) - dy_mean
            sxx += sx * sx
            sxy += sx * sy
            syy += sy * sy
            # c_ij: the sum of target coordinate i times source coordinate j.
            cxx += dx * sx
            cxy += dx * sy
            cyx += dy * sx
            cyy += dy * sy
    # The best rotation-and-scale, as the complex number sum(dst * conj(src)) / sum|src|^2.
    spread = sxx + syy
    real, imaginary = 1.0, 0.0
    if count >= 2 and spread > 0:
        real, imaginary = (cxx + cyy) / spread, (cyx - cxy) / spread
    a, b, c, d = real, -imaginary, imaginary, real
    kind = min(count, SIMILARITY)
    if affine and count >= 3 and _well_spread(sxx, sxy, syy):
        det = sxx * syy - sxy * sxy
        a, b = (cxx * syy - cxy * sxy) / det, (cxy * sxx - cxx * sxy) / det
        c, d = (cyx * syy - cyy * sxy) / det, (cyy * sxx - cyx * sxy) / det
        kind = AFFINE
    offset_x, offset_y = np.nan, np.nan
    if count >= 1:
        offset_x = dx_mean - a * sx_mean - b * sy_mean
        offset_y = dy_mean - c * sx_mean - d * sy_mean
    return (a, b, c, d, offset_x, offset_y), kind


@kernel
def _well_spread(xx: float, xy: float, yy: float) -> bool:
    """The smaller principal spread of the covariances ``xx``, ``xy``, ``yy`` is wide enough.

    The smaller eigenvalue (closed form) must exceed :data:`MIN_AFFINE_SPREAD` times the
    larger.
    """
    half_sum = 0.5 * (xx + yy)
    radius = np.hypot(0.5 * (xx - yy), xy)
    return half_sum - radius > MIN_AFFINE_SPREAD * max(half_sum + radius, 1e-300)


@kernel
def _finite_or_zero(value: float) -> float:
    """``value``, or 0 where it is NaN."""
    return 0.0 if np.isnan(value) else value


@kernel
def _fit_many(
    source: np.ndarray, target: np.ndarray, weights: np.ndarray, affine: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`fit_map` for each of ``N`` fits: ``(N, 2, 2)``, ``(N, 2)``, ``(N,) int64``."""
    n_fits = weights.shape[0]
    linear, offset = np.empty((n_fits, 2, 2)), np.empty((n_fits, 2))
    kind = np.empty(n_fits, dtype=np.int64)
    for n in range(n_fits):
        (a, b, c, d, x, y), kind[n] = fit_map(source[n], target[n], weights[n], affine)
        linear[n, 0, 0], linear[n, 0, 1], linear[n, 1, 0], linear[n, 1, 1] = a, b, c, d
        offset[n, 0], offset[n, 1] = x, y
    return linear, offset, kind


def fit_maps(
    source: np.ndarray, target: np.ndarray, weights: np.ndarray, *, affine: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit source-to-target maps ``x -> linear @ x + offset`` by weighted least squares.

    Parameters
    ----------
    source, target
        ``(N, K, 2) float64``, pixels: ``N`` pairs of configurations of ``K`` points
        (NaN allowed where the weight is 0).
    weights
        ``(N, K) bool``: the points that take part in each fit.
    affine
        Fit affine maps where the points allow; ``False`` fits similarities at most.

    Returns
    -------
    linear
        ``(N, 2, 2) float64``.
    offset
        ``(N, 2) float64``, NaN where no point took part.
    kind
        ``(N,) int64``: the map fitted, :data:`AFFINE` (3 or more well-spread points),
        :data:`SIMILARITY` (2 points, or collinear ones), :data:`TRANSLATION` (1 point) or
        :data:`NO_MAP` (none).
    """
    return _fit_many(np.asarray(source, dtype=np.float64), np.asarray(target, dtype=np.float64),
                     np.asarray(weights, dtype=np.bool_), affine)


def fit_maps_from_shape(
    shape: np.ndarray, target: np.ndarray, weights: np.ndarray, *, affine: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit the maps from one ``shape`` to many targets (:func:`fit_maps`, shape repeated).

    With the source and the points that take part fixed, the fitted map is an affine
    function of the target points. It is found once per distinct set of points, by
    fitting the zero target and the unit targets, and applied to every target fitted on
    that set as one matrix product: the same maps as :func:`fit_maps`, to rounding.

    Parameters
    ----------
    shape
        ``(K, 2) float64``: the source points of every fit.
    target, weights, affine
        ``(N, K, 2)``, ``(N, K) bool``: as for :func:`fit_maps`.

    Returns
    -------
    linear, offset, kind
        As for :func:`fit_maps`.
    """
    n_targets = weights.shape[0]
    first, set_of, order, sizes = _point_sets(_member_bits(weights))
    constant, slope, kind = _probe_maps(shape, weights[first], affine)
    flat_target = np.where(np.repeat(weights, 2, axis=1), target.reshape(n_targets, -1), 0.0)
    if first.size == 1:
        fitted = flat_target @ slope[0] + constant[0]
    else:
        by_set = flat_target[order]
        stops = np.cumsum(sizes)
        fitted = np.empty((n_targets, 6))
        for index, (start, stop) in enumerate(zip(stops - sizes, stops, strict=True)):
            fitted[order[start:stop]] = by_set[start:stop] @ slope[index] + constant[index]
    return fitted[:, :4].reshape(n_targets, 2, 2), fitted[:, 4:], kind[set_of]


@kernel
def _point_sets(bits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Group fits by their set of points.

    Parameters
    ----------
    bits
        ``(N,) int64``: each fit's set of points (:func:`_member_bits`).

    Returns
    -------
    first
        ``(S,) int64``: the first fit of each distinct set, sets in ascending ``bits``.
    set_of
        ``(N,) int64``: the set of each fit.
    order
        ``(N,) int64``: the fits, set after set (in order within a set).
    sizes
        ``(S,) int64``: the fits of each set.
    """
    order = np.argsort(bits, kind="mergesort")
    set_of = np.empty(bits.size, dtype=np.int64)
    first, sizes = np.empty(bits.size, dtype=np.int64), np.zeros(bits.size, dtype=np.int64)
    n_sets = 0
    for rank in range(bits.size):
        fit = order[rank]
        if rank == 0 or bits[fit] != bits[order[rank - 1]]:
            first[n_sets] = fit
            n_sets += 1
        set_of[fit] = n_sets - 1
        sizes[n_sets - 1] += 1
    return first[:n_sets].copy(), set_of, order, sizes[:n_sets].copy()


@kernel
def _probe_maps(
    shape: np.ndarray, weights: np.ndarray, affine: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The maps from ``shape`` as affine functions of the target, per set of points.

    Parameters
    ----------
    shape
        ``(K, 2) float64``: the source points.
    weights
        ``(S, K) bool``: the sets of points that take part.
    affine
        As for :func:`fit_maps`.

    Returns
    -------
    constant
        ``(S, 6) float64``: the map to the zero target (linear part row by row, offset).
    slope
        ``(S, 2 K, 6) float64``: the change of the map per unit of each flattened target
        coordinate (the map to that unit target minus ``constant``).
    kind
        ``(S,) int64``: the kind of map each set allows (:func:`fit_maps`).
    """
    n_sets, n_points = weights.shape
    probe = np.zeros((n_points, 2))
    constant, slope = np.empty((n_sets, 6)), np.empty((n_sets, 2 * n_points, 6))
    kind = np.empty(n_sets, dtype=np.int64)
    for s in range(n_sets):
        base, kind[s] = fit_map(shape, probe, weights[s], affine)
        for i in range(6):
            constant[s, i] = base[i]
        for unit in range(2 * n_points):
            probe[unit // 2, unit % 2] = 1.0
            moved, _ = fit_map(shape, probe, weights[s], affine)
            probe[unit // 2, unit % 2] = 0.0
            for i in range(6):
                slope[s, unit, i] = moved[i] - base[i]
    return constant, slope, kind


def map_points(
    source: np.ndarray,
    target: np.ndarray,
    weights: np.ndarray,
    query: np.ndarray,
    *,
    affine: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Fit source-to-target maps (see :func:`fit_maps`) and apply them to query points.

    Parameters
    ----------
    source, target, weights, affine
        As for :func:`fit_maps`.
    query
        ``(N, 2) float64``: a point of each source configuration to carry over.

    Returns
    -------
    mapped
        ``(N, 2) float64``: each query point carried to its target configuration, NaN where
        no point took part in the fit.
    ok
        ``(N,) bool``: a map could be fitted.
    """
    linear, offset, kind = fit_maps(source, target, weights, affine=affine)
    return apply_linear(linear, query) + offset, kind > NO_MAP
