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


def _centred(
    points: np.ndarray, taking_part: np.ndarray, count: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return the weighted means and the centred coordinates of ``(N, K, 2)`` points.

    ``taking_part`` is ``(K, N) bool`` and ``count`` ``(N,)`` its column sums. Returns the
    ``(2, N)`` means and ``(2, K, N)`` coordinate planes about them, 0 where a point does
    not take part (points along the middle axis: numpy reduces a short last axis slowly).
    A NaN coordinate of a point taking part counts as 0.
    """
    planes = points.transpose(2, 1, 0)
    planes = np.where(taking_part & ~np.isnan(planes), planes, 0.0)
    mean = planes.sum(axis=1) / np.maximum(count, 1)
    return mean, np.where(taking_part, planes - mean[:, None], 0.0)


def _well_spread(xx: np.ndarray, xy: np.ndarray, yy: np.ndarray) -> np.ndarray:
    """``(N,) bool``: the smaller principal spread of covariances is wide enough.

    ``xx``, ``xy``, ``yy`` are the covariances' entries, ``(N,)`` each; the smaller
    eigenvalue (closed form) must exceed :data:`MIN_AFFINE_SPREAD` times the larger.
    """
    half_sum = 0.5 * (xx + yy)
    radius = np.hypot(0.5 * (xx - yy), xy)
    return half_sum - radius > MIN_AFFINE_SPREAD * np.maximum(half_sum + radius, 1e-300)


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
    taking_part = np.ascontiguousarray(weights.T)
    count = taking_part.sum(axis=0)
    (sx_mean, sy_mean), (sx, sy) = _centred(source, taking_part, count)
    (dx_mean, dy_mean), (dx, dy) = _centred(target, taking_part, count)
    sxx, sxy, syy = (sx * sx).sum(axis=0), (sx * sy).sum(axis=0), (sy * sy).sum(axis=0)
    # cross_ij = sum of target coordinate i times source coordinate j.
    cxx, cxy = (dx * sx).sum(axis=0), (dx * sy).sum(axis=0)
    cyx, cyy = (dy * sx).sum(axis=0), (dy * sy).sum(axis=0)

    # The best rotation-and-scale, as the complex number sum(dst * conj(src)) / sum|src|^2.
    spread = sxx + syy
    turns = (count >= 2) & (spread > 0)
    real = np.divide(cxx + cyy, spread, out=np.ones_like(spread), where=turns)
    imaginary = np.divide(cyx - cxy, spread, out=np.zeros_like(spread), where=turns)
    linear = np.stack([real, -imaginary, imaginary, real])

    kind = np.minimum(count, SIMILARITY)
    if affine:
        spread_ok = (count >= 3) & _well_spread(sxx, sxy, syy)
        det = np.where(spread_ok, sxx * syy - sxy * sxy, 1.0)
        general = np.stack([cxx * syy - cxy * sxy, cxy * sxx - cxx * sxy,
                            cyx * syy - cyy * sxy, cyy * sxx - cyx * sxy]) / det
        linear = np.where(spread_ok, general, linear)
        kind = np.where(spread_ok, AFFINE, kind)

    offset = np.stack([dx_mean - linear[0] * sx_mean - linear[1] * sy_mean,
                       dy_mean - linear[2] * sx_mean - linear[3] * sy_mean], axis=-1)
    return (linear.T.reshape(-1, 2, 2), np.where((count >= 1)[:, None], offset, np.nan),
            kind)


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
    n_targets, n_points = weights.shape
    n_params = 2 * n_points + 1
    point_sets, first, set_of = np.unique(_member_bits(weights), return_index=True,
                                          return_inverse=True)
    probes = np.concatenate([np.zeros((1, 2 * n_points)), np.eye(2 * n_points)])
    linear, offset, kind = fit_maps(
        np.broadcast_to(shape, (point_sets.size * n_params, n_points, 2)),
        np.tile(probes.reshape(n_params, n_points, 2), (point_sets.size, 1, 1)),
        np.repeat(weights[first], n_params, axis=0), affine=affine)
    maps = np.concatenate([linear.reshape(-1, 4), offset], axis=1)
    maps = maps.reshape(point_sets.size, n_params, 6)
    constant, slope = maps[:, 0], maps[:, 1:] - maps[:, :1]
    set_of = set_of.ravel()
    flat_target = np.where(np.repeat(weights, 2, axis=1), target.reshape(n_targets, -1), 0.0)
    if point_sets.size == 1:
        fitted = flat_target @ slope[0] + constant[0]
    else:
        order = np.argsort(set_of, kind="stable")
        by_set = flat_target[order]
        sizes = np.bincount(set_of)
        stops = np.cumsum(sizes)
        fitted = np.empty((n_targets, 6))
        for index, (start, stop) in enumerate(zip(stops - sizes, stops, strict=True)):
            fitted[order[start:stop]] = by_set[start:stop] @ slope[index] + constant[index]
    return fitted[:, :4].reshape(n_targets, 2, 2), fitted[:, 4:], kind[::n_params][set_of]


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
