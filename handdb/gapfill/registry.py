"""What a gap-filling method returns, and :func:`fill_gaps`, the one entry point.

A method is a function ``(uv, missing, skeleton, **params) -> MethodOutput``: ``uv`` is a
``(T, J, 2)`` copy of the tracks with NaN at every missing point, ``missing`` the
``(T, J) bool`` mask of those points. It returns the tracks with the missing points it could
fill filled (NaN where it declined) and notes on what it did. :func:`fill_gaps` hides the
missing points from the method, keeps every observed point as it was, and records which
point was filled by what.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from handdb.clip import IMAGES, SAMPLINGS, VIDEO, finite_points
from handdb.errors import GapFillError
from handdb.gapfill.gaps import find_gaps, mask_points
from handdb.gapfill.methods import DEFAULT_METHOD, METHODS, MethodInfo
from handdb.hand.skeletons import Skeleton

#: Flag kinds. A gap at the start of the clip (the joint is missing in the first frame).
LEADING = "leading"
#: A gap that runs to the last frame.
TRAILING = "trailing"
#: A joint missing in every frame of the clip.
WHOLE_CLIP = "whole_clip"
#: A thesis method had fewer earlier frames than it needs and used a simpler rule.
SHORT_HISTORY = "short_history"
#: Missing points the method left unfilled (NaN).
UNFILLED = "unfilled"


@dataclass(frozen=True)
class GapFlag:
    """A note on one gap (or part of one): what was special and what was done.

    ``start`` and ``stop`` are frame numbers, ``stop`` exclusive.
    """

    joint: str
    start: int
    stop: int
    kind: str
    note: str


@dataclass(frozen=True)
class MethodOutput:
    """What a method returns.

    Attributes
    ----------
    uv
        ``(T, J, 2) float64``, pixels: the tracks with the missing points filled, NaN where
        the method could not fill.
    labels
        ``(T, J)`` str: the name of the rule that filled each point (read at the missing
        points only), for methods that combine several; ``None`` to label every filled
        point with the method's name.
    flags
        Notes on particular gaps.
    """

    uv: np.ndarray
    labels: np.ndarray | None = None
    flags: tuple[GapFlag, ...] = ()


@dataclass(frozen=True)
class FillResult:
    """The result of :func:`fill_gaps`.

    Attributes
    ----------
    uv
        ``(T, J, 2) float64``, pixels: observed points unchanged, missing points filled
        (NaN where the method could not fill).
    filled
        ``(T, J) bool``: the point was missing and has been filled.
    method
        The method asked for.
    fill_method
        ``(T, J)`` str: the rule that filled each point (``""`` where not filled).
    flags
        Notes on leading, trailing and whole-clip gaps, short histories, unfilled points.
    """

    uv: np.ndarray
    filled: np.ndarray
    method: str
    fill_method: np.ndarray
    flags: tuple[GapFlag, ...]

    def flags_of(self, kind: str) -> tuple[GapFlag, ...]:
        """Return the flags of one kind."""
        return tuple(f for f in self.flags if f.kind == kind)


def _edge_flags(missing: np.ndarray, skeleton: Skeleton) -> list[GapFlag]:
    gaps = find_gaps(missing)
    edges = gaps.select(gaps.leading | gaps.trailing)
    flags = []
    for j, start, stop, whole, leading in zip(
        edges.joint, edges.start, edges.stop, edges.whole_clip, edges.leading, strict=True
    ):
        if whole:
            kind, note = WHOLE_CLIP, "never observed in the clip"
        elif leading:
            kind, note = LEADING, "missing from the first frame: no earlier data"
        else:
            kind, note = TRAILING, "missing to the last frame: no later data"
        flags.append(GapFlag(skeleton.joints[j], int(start), int(stop), kind, note))
    return flags


def _unfilled_flags(unfilled: np.ndarray, skeleton: Skeleton) -> list[GapFlag]:
    gaps = find_gaps(unfilled)
    return [
        GapFlag(skeleton.joints[j], int(a), int(b), UNFILLED, "the method left these points NaN")
        for j, a, b in zip(gaps.joint, gaps.start, gaps.stop, strict=True)
    ]


def _fill_each_image(info: MethodInfo, uv: np.ndarray, missing: np.ndarray,
                     skeleton: Skeleton, params: dict[str, object]) -> MethodOutput:
    """Run a method on every frame on its own, as if each were a clip of one frame.

    Independent images share no time: what fills a point is the frame's own points and the
    hand model (a DIP on its chord, a joint never seen from the rest pose fitted to the
    frame), never a neighbouring image. A frame that observes no point, or too little for
    the method to fill (:class:`~handdb.errors.GapFillError`), is left unfilled; the clip
    is refused only when that is every frame.
    """
    filled = uv.copy()
    labels = np.full(missing.shape, "", dtype=object)
    has_labels = False
    flags: list[GapFlag] = []
    refusals: list[GapFillError] = []
    for frame in np.flatnonzero(~missing.all(axis=1)):
        try:
            one = info.fill(uv[frame:frame + 1], missing[frame:frame + 1], skeleton, **params)
        except GapFillError as error:
            refusals.append(error)
            continue
        filled[frame] = one.uv[0]
        if one.labels is not None:
            labels[frame], has_labels = one.labels[0], True
        flags += [replace(flag, start=flag.start + int(frame), stop=flag.stop + int(frame))
                  for flag in one.flags]
    if refusals and len(refusals) == int((~missing.all(axis=1)).sum()):
        raise refusals[0]
    return MethodOutput(filled, labels=labels.astype(str) if has_labels else None,
                        flags=tuple(flags))


def fill_gaps(
    uv: np.ndarray,
    observed: np.ndarray,
    skeleton: Skeleton,
    method: str = DEFAULT_METHOD,
    *,
    sampling: str = VIDEO,
    **params: object,
) -> FillResult:
    """Fill the missing points of 2D tracks.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels; values at unobserved points are ignored.
    observed
        ``(T, J) bool``: the point is known (present and confident enough).
    skeleton
        The skeleton the joint axis follows.
    method
        A registered method name (see :data:`METHODS`); :data:`DEFAULT_METHOD` by default.
    sampling
        :data:`~handdb.clip.VIDEO` (frames in time order) or :data:`~handdb.clip.IMAGES`
        (independent images: the method runs on each frame on its own, and a frame that
        observes no point stays unfilled).
    **params
        Parameters of the method.

    Returns
    -------
    FillResult
        A filled copy; ``uv`` and ``observed`` are not modified.

    Raises
    ------
    UnknownNameError
        If ``method`` is not registered.
    GapFillError
        If the method cannot fill the clip from what it observes (``auto``: a joint never
        observed in a clip no frame of which observes enough of the palm to place it,
        :func:`~handdb.gapfill.auto.check_placeable`).
    ValueError
        If the shapes of ``uv``, ``observed`` and ``skeleton`` disagree, or ``sampling``
        is unknown.
    """
    info = METHODS[method]
    uv = np.asarray(uv, dtype=np.float64)
    observed = np.asarray(observed, dtype=bool)
    if uv.ndim != 3 or uv.shape[1:] != (skeleton.n_joints, 2) or observed.shape != uv.shape[:2]:
        raise ValueError(
            f"uv must be (T, {skeleton.n_joints}, 2) and observed (T, {skeleton.n_joints}) for "
            f"skeleton '{skeleton.name}'; got {uv.shape} and {observed.shape}"
        )
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, got {sampling!r}")
    missing = ~observed | ~(np.isfinite(uv[..., 0]) & np.isfinite(uv[..., 1]))
    frame, joint = mask_points(missing)
    hidden = uv.copy()
    hidden[frame, joint] = np.nan
    output = (info.fill(hidden, missing, skeleton, **params) if sampling == VIDEO
              else _fill_each_image(info, hidden, missing, skeleton, params))
    filled_uv = uv.copy()
    filled_uv[frame, joint] = output.uv[frame, joint]
    done = finite_points(filled_uv[frame, joint])
    frame, joint = frame[done], joint[done]
    filled = np.zeros_like(missing)
    filled[frame, joint] = True
    labels = np.asarray(method if output.labels is None else output.labels, dtype=str)
    fill_method = np.zeros(missing.shape, dtype=labels.dtype)
    fill_method[frame, joint] = labels if labels.ndim == 0 else labels[frame, joint]
    edges = _edge_flags(missing, skeleton)
    if sampling == IMAGES:
        # the first and last image are no edges of anything
        edges = [flag for flag in edges if flag.kind == WHOLE_CLIP]
    flags = (
        *edges,
        *output.flags,
        *_unfilled_flags(missing & ~filled, skeleton),
    )
    return FillResult(filled_uv, filled, method, fill_method, flags)
