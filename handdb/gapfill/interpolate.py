"""Interpolation across gaps from both sides: linear, cubic spline and PCHIP.

Offline, the frames after a gap are known, so an interior gap is bridged by a curve through
the joint's observed samples (scipy's ``CubicSpline`` with not-a-knot ends, or
``PchipInterpolator``, which never overshoots its samples). Gaps longer than ``max_gap``
frames are left unfilled. A leading or trailing gap has samples on one side only: the
nearest observed value is held (flagged by :func:`~handdb.gapfill.registry.fill_gaps`);
a joint never observed is left unfilled.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from handdb.compiled import kernel
from handdb.errors import UnknownNameError
from handdb.gapfill.gaps import Gaps, find_gaps
from handdb.gapfill.registry import MethodOutput
from handdb.hand.skeletons import Skeleton

#: Interpolation kinds.
KINDS = ("linear", "cubic", "pchip")


@kernel
def _sign(value: float) -> float:
    """``np.sign`` of a float: 1, -1, 0, or NaN for NaN."""
    if value > 0:
        return 1.0
    if value < 0:
        return -1.0
    return value if value != value else 0.0


@kernel
def _edge_slope(h0: int, h1: int, m0: float, m1: float) -> float:
    """PCHIP's one-sided three-point slope at an end sample, kept shape-preserving.

    ``h0``, ``m0``: width (frames) and secant of the end interval; ``h1``, ``m1``: of the
    next one.
    """
    slope = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if _sign(slope) != _sign(m0):
        return 0.0
    if _sign(m0) != _sign(m1) and abs(slope) > 3 * abs(m0):
        return 3 * m0
    return slope


@kernel
def _inner_slope(h_before: int, h_after: int, m_before: float, m_after: float) -> float:
    """PCHIP's slope at an inner sample: 0 at an extremum, else a weighted harmonic mean."""
    if _sign(m_before) != _sign(m_after) or m_before == 0 or m_after == 0:
        return 0.0
    w_before, w_after = 2 * h_after + h_before, h_after + 2 * h_before
    return 1.0 / ((w_before / m_before + w_after / m_after) / (w_before + w_after))


def _pchip_in_gaps(uv: np.ndarray, gaps: Gaps) -> np.ndarray:
    """Evaluate every joint's PCHIP through its observed samples in its gaps, all at once.

    PCHIP is local: in a gap it is the cubic Hermite between the samples bounding the gap,
    whose slopes depend on one more sample either side (the one-sided end formula where
    there is none; a straight line through a joint's only two samples). Leading and
    trailing gaps hold the nearest sample. Equals scipy's ``PchipInterpolator`` per joint.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, NaN where missing.
    gaps
        Every gap of the joints observed at least once (as :func:`find_gaps` orders them).

    Returns
    -------
    numpy.ndarray
        ``(N, 2) float64``: the values at the points of ``gaps.frames()``, in order.
    """
    return _pchip_kernel(uv, gaps.joint, gaps.start, gaps.stop)


@kernel
def _pchip_kernel(
    uv: np.ndarray, joint: np.ndarray, start: np.ndarray, stop: np.ndarray
) -> np.ndarray:
    """:func:`_pchip_in_gaps` on the gaps' arrays, ``(G,) int64`` each.

    A gap's samples: ``before`` and ``after`` bound it; ``earlier`` and ``later`` are the
    joint's samples next to them, found from the neighbouring gaps of the joint (gaps are
    ordered by joint, then start): the last observed frame before ``before`` (-1 if none)
    and the first after ``after`` (``T`` if none).
    """
    n_frames, n_gaps = uv.shape[0], joint.size
    values = np.empty((np.sum(stop - start), 2))
    point = 0
    for g in range(n_gaps):
        leading, trailing = start[g] == 0, stop[g] == n_frames
        before = stop[g] if leading else start[g] - 1
        after = before if trailing else stop[g]
        same_before = g > 0 and joint[g - 1] == joint[g]
        same_after = g + 1 < n_gaps and joint[g + 1] == joint[g]
        earlier = start[g - 1] - 1 if same_before and stop[g - 1] == before else before - 1
        later = stop[g + 1] if same_after and start[g + 1] == after + 1 else after + 1
        earlier, later = -1 if leading else earlier, n_frames if trailing else later
        width, h_earlier = max(after - before, 1), max(before - earlier, 1)
        h_later = max(later - after, 1)
        for k in range(2):
            y_before, y_after = uv[before, joint[g], k], uv[after, joint[g], k]
            secant = (y_after - y_before) / width
            m_earlier = (y_before - uv[max(earlier, 0), joint[g], k]) / h_earlier
            m_later = (uv[min(later, n_frames - 1), joint[g], k] - y_after) / h_later
            if earlier >= 0:
                slope_before = _inner_slope(h_earlier, width, m_earlier, secant)
            elif later < n_frames:
                slope_before = _edge_slope(width, h_later, secant, m_later)
            else:
                slope_before = secant
            if later < n_frames:
                slope_after = _inner_slope(width, h_later, secant, m_later)
            elif earlier >= 0:
                slope_after = _edge_slope(width, h_earlier, secant, m_earlier)
            else:
                slope_after = secant
            cubic_share = (slope_before + slope_after - 2 * secant) / width
            cubic = cubic_share / width
            quadratic = (secant - slope_before) / width - cubic_share
            for frame in range(start[g], stop[g]):
                step = float(frame - before)
                value = ((cubic * step + quadratic) * step + slope_before) * step + y_before
                values[point + frame - start[g], k] = y_before if leading or trailing else value
        point += stop[g] - start[g]
    return values


def _curve(frames: np.ndarray, values: np.ndarray, kind: str, at: np.ndarray) -> np.ndarray:
    at = np.clip(at, frames[0], frames[-1])
    if kind == "linear" or frames.size < 3:
        return np.stack([np.interp(at, frames, values[:, k]) for k in range(2)], axis=-1)
    from scipy.interpolate import CubicSpline  # 0.6 s to import; only cubic fills use it

    return CubicSpline(frames, values)(at)


def interpolate_gaps(
    uv: np.ndarray, missing: np.ndarray, kind: str = "pchip", max_gap: int | None = None
) -> np.ndarray:
    """Bridge interior gaps of at most ``max_gap`` frames; hold the edge values.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, NaN where missing.
    missing
        ``(T, J) bool``.
    kind
        ``"linear"``, ``"cubic"`` or ``"pchip"``.
    max_gap
        Longest interior gap to bridge, frames; ``None`` for no limit.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: a filled copy, NaN where a gap was too long or the joint
        was never observed.
    """
    if kind not in KINDS:
        raise UnknownNameError("interpolation kind", kind, tuple(KINDS))
    gaps = find_gaps(missing)
    too_long = gaps.interior & (gaps.length > (np.inf if max_gap is None else max_gap))
    filled = uv.copy()
    if kind == "pchip":
        seen_once = gaps.select(~gaps.whole_clip)
        _, frame, joint = seen_once.frames()
        filled[frame, joint] = _pchip_in_gaps(uv, seen_once)
    else:
        frames_all = np.arange(uv.shape[0])
        for j in np.unique(gaps.joint[~gaps.whole_clip]):
            known = ~missing[:, j]
            at = frames_all[~known]
            filled[at, j] = _curve(frames_all[known], uv[known, j], kind, at)
    _, frame, joint = gaps.select(too_long).frames()
    filled[frame, joint] = np.nan
    return filled


def interpolation_method(kind: str) -> Callable[..., MethodOutput]:
    """The gap-filling method that interpolates each gap with ``kind``.

    See :func:`interpolate_gaps`; the method's one parameter is ``max_gap``.
    """

    def fill(
        uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, *, max_gap: int | None = None
    ) -> MethodOutput:
        return MethodOutput(interpolate_gaps(uv, missing, kind, max_gap))

    fill.__name__ = f"fill_{kind}"
    return fill
