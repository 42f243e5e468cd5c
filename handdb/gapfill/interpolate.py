"""Interpolation across gaps from both sides: linear, cubic spline and PCHIP.

Offline, the frames after a gap are known, so an interior gap is bridged by a curve through
the joint's observed samples (scipy's ``CubicSpline`` with not-a-knot ends, or
``PchipInterpolator``, which never overshoots its samples). Gaps longer than ``max_gap``
frames are left unfilled. A leading or trailing gap has samples on one side only: the
nearest observed value is held (flagged by :func:`~handdb.gapfill.registry.fill_gaps`);
a joint never observed is left unfilled.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from handdb.gapfill.gaps import Gaps, find_gaps
from handdb.gapfill.registry import OFFLINE, MethodOutput, register
from handdb.skeletons import Skeleton

#: Interpolation kinds.
KINDS = ("linear", "cubic", "pchip")


def _edge_slope(h0: np.ndarray, h1: np.ndarray, m0: np.ndarray, m1: np.ndarray) -> np.ndarray:
    """PCHIP's one-sided three-point slope at an end sample, kept shape-preserving.

    ``h0``, ``m0``: width and secant of the end interval; ``h1``, ``m1``: of the next one.
    """
    slope = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    wrong_sign = np.sign(slope) != np.sign(m0)
    overshoots = (np.sign(m0) != np.sign(m1)) & (np.abs(slope) > 3 * np.abs(m0))
    return np.where(wrong_sign, 0.0, np.where(overshoots, 3 * m0, slope))


def _inner_slope(
    h_before: np.ndarray, h_after: np.ndarray, m_before: np.ndarray, m_after: np.ndarray
) -> np.ndarray:
    """PCHIP's slope at an inner sample: 0 at an extremum, else a weighted harmonic mean."""
    w_before, w_after = 2 * h_after + h_before, h_after + 2 * h_before
    turns = (np.sign(m_before) != np.sign(m_after)) | (m_before == 0) | (m_after == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = (w_before / m_before + w_after / m_after) / (w_before + w_after)
        return np.where(turns, 0.0, 1.0 / mean)


def _outer_samples(
    gaps: Gaps, before: np.ndarray, after: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The joint's samples next to the ``before`` and ``after`` samples of each gap.

    Gaps are ordered by joint, then start, so a sample missing next to ``before`` (or
    ``after``) belongs to the previous (or next) gap of the joint, and the sample beyond
    is the one bounding that gap.

    Returns
    -------
    earlier, later
        ``(G,) int64``: the last observed frame before ``before`` (-1 if none) and the first
        after ``after`` (``T`` if none).
    """
    same_joint = gaps.joint[1:] == gaps.joint[:-1]
    previous_touches = np.zeros(len(gaps), dtype=bool)
    previous_touches[1:] = same_joint & (gaps.stop[:-1] == before[1:])
    earlier = np.where(previous_touches, np.roll(gaps.start, 1) - 1, before - 1)
    next_touches = np.zeros(len(gaps), dtype=bool)
    next_touches[:-1] = same_joint & (gaps.start[1:] == after[:-1] + 1)
    later = np.where(next_touches, np.roll(gaps.stop, -1), after + 1)
    return (np.where(gaps.leading, -1, earlier),
            np.where(gaps.trailing, gaps.n_frames, later))


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
    n_frames = uv.shape[0]
    joint = gaps.joint
    before = np.where(gaps.leading, gaps.stop, gaps.start - 1)
    after = np.where(gaps.trailing, before, gaps.stop)
    earlier, later = _outer_samples(gaps, before, after)
    has_earlier, has_later = (earlier >= 0)[:, None], (later < n_frames)[:, None]
    y_before, y_after = uv[before, joint], uv[after, joint]
    y_earlier = uv[np.maximum(earlier, 0), joint]
    y_later = uv[np.minimum(later, n_frames - 1), joint]
    width = np.maximum(after - before, 1)[:, None]
    h_earlier = np.maximum(before - earlier, 1)[:, None]
    h_later = np.maximum(later - after, 1)[:, None]
    secant = (y_after - y_before) / width
    m_earlier = (y_before - y_earlier) / h_earlier
    m_later = (y_later - y_after) / h_later
    slope_before = np.where(has_earlier, _inner_slope(h_earlier, width, m_earlier, secant),
                            np.where(has_later, _edge_slope(width, h_later, secant, m_later),
                                     secant))
    slope_after = np.where(has_later, _inner_slope(width, h_later, secant, m_later),
                           np.where(has_earlier, _edge_slope(width, h_earlier, secant,
                                                             m_earlier), secant))
    cubic_share = (slope_before + slope_after - 2 * secant) / width
    cubic = cubic_share / width
    quadratic = (secant - slope_before) / width - cubic_share
    gap, frame, _ = gaps.frames()
    step = (frame - before[gap])[:, None].astype(np.float64)
    value = ((cubic[gap] * step + quadratic[gap]) * step + slope_before[gap]) * step
    value += y_before[gap]
    edge = (gaps.leading | gaps.trailing)[gap, None]
    return np.where(edge, y_before[gap], value)


def _curve(frames: np.ndarray, values: np.ndarray, kind: str, at: np.ndarray) -> np.ndarray:
    at = np.clip(at, frames[0], frames[-1])
    if kind == "linear" or frames.size < 3:
        return np.stack([np.interp(at, frames, values[:, k]) for k in range(2)], axis=-1)
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
        raise ValueError(f"unknown interpolation kind '{kind}'; known: {', '.join(KINDS)}")
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


def _register(kind: str, summary: str) -> None:
    def fill(
        uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, *, max_gap: int | None = None
    ) -> MethodOutput:
        return MethodOutput(interpolate_gaps(uv, missing, kind, max_gap))

    fill.__name__ = f"fill_{kind}"
    fill.__doc__ = f"{summary.capitalize()} (see :func:`interpolate_gaps`)."
    register(kind, OFFLINE, summary)(fill)


_register("linear", "linear interpolation across each gap")
_register("cubic", "cubic spline through the observed samples")
_register("pchip", "shape-preserving cubic (PCHIP) through the observed samples")
