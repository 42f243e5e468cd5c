"""What a gap fill could not know, in words: the notes a stored clip carries.

A joint the detector never reported is placed by the hand model, and so is a joint that
a part of the clip never shows (a segment between frames left without positions, an
independent image); frames that observe nothing outside a short interior run stay
without positions. None is a refusal, and none may pass silently: :func:`fill_caveats`
says each, for ``clips.flag_reasons``, and :func:`caveat_rows` marks their rows.
"""

from __future__ import annotations

import numpy as np

from handdb.clip import finite_points
from handdb.gapfill.auto import MODEL_RULES
from handdb.gapfill.gaps import find_gaps
from handdb.gapfill.registry import FillResult
from handdb.hand.skeletons import Skeleton

#: Runs of frames named in a caveat, at most.
SHOWN_RUNS = 3


def _runs(frames: np.ndarray) -> str:
    """``frames`` ``(T,) bool`` as its first runs, ``"0-1, 7"``, and how many more."""
    runs = find_gaps(frames[:, None])
    shown = ", ".join(f"{start}-{stop - 1}" if stop - start > 1 else f"{start}"
                      for start, stop in zip(runs.start[:SHOWN_RUNS], runs.stop[:SHOWN_RUNS],
                                             strict=True))
    more = f" and {len(runs) - SHOWN_RUNS} more runs" if len(runs) > SHOWN_RUNS else ""
    return shown + more


def _never_detected(result: FillResult, skeleton: Skeleton, joint: str) -> str:
    """The caveat of one joint missing in every frame."""
    index = skeleton.index(joint)
    placed = result.filled[:, index]
    if not placed.any():
        return f"{joint} never detected: left without positions"
    rules = sorted(set(result.fill_method[placed, index]))
    how = ("placed by the hand model" if set(rules) <= set(MODEL_RULES)
           else "filled by gap filling")
    where = "" if placed.all() else f" in {int(placed.sum())} of {placed.size} frames"
    return f"{joint} never detected: {how} ({', '.join(rules)}){where}"


def never_detected(result: FillResult) -> np.ndarray:
    """``(J,) bool``: the joints no frame observed (each point filled or left missing).

    Read from the arrays, not the fill's notes, so a fill read back from the store (which
    keeps no notes) says the same.
    """
    observed = ~result.filled & finite_points(result.uv)
    return ~observed.any(axis=0)


def empty_frames(result: FillResult) -> np.ndarray:
    """``(T,) bool``: the frames left without any position (none observed, none filled)."""
    return ~np.isfinite(result.uv).any(axis=(1, 2))


def placed_by_model(result: FillResult) -> np.ndarray:
    """``(T, J) bool``: the points the hand model placed (labelled with :data:`MODEL_RULES`)."""
    return result.filled & np.isin(result.fill_method, MODEL_RULES)


def caveat_rows(result: FillResult) -> np.ndarray:
    """``(T, J) bool``: the points a caveat of :func:`fill_caveats` is about.

    Every point of a joint never detected, every point of a frame left without positions,
    and every point the hand model placed.
    """
    return (empty_frames(result)[:, None] | never_detected(result)[None, :]
            | placed_by_model(result))


def _placed_in_part(result: FillResult, skeleton: Skeleton, joint: int) -> str:
    """The caveat of a joint detected in some frames and placed by the hand model in others."""
    placed = placed_by_model(result)[:, joint]
    rules = ", ".join(sorted(set(result.fill_method[placed, joint])))
    return (f"{skeleton.joints[joint]} detected in part of the clip only: placed by the hand "
            f"model ({rules}) in {int(placed.sum())} of {placed.size} frames "
            f"({_runs(placed)}), where the part of the clip they belong to never shows it")


def fill_caveats(result: FillResult, skeleton: Skeleton) -> tuple[str, ...]:
    """What the gap fill of a clip could not know, one sentence each.

    Parameters
    ----------
    result
        The clip's gap fill.
    skeleton
        The skeleton of ``result``'s joint axis.

    Returns
    -------
    tuple of str
        A joint never detected and how it was placed (``"little_tip never detected:
        placed by the hand model (rest-pose)"``), a joint detected in some segments (or
        images) and placed by the hand model in the others (``"little_tip detected in
        part of the clip only: placed by the hand model (rest-pose) in 23 of 64 frames
        (41-63), ..."``), then the frames left without positions (``"2 of 9 frames (0-1)
        observe no point and were not filled: stored without positions"``); empty when
        the fill knew everything it filled.
    """
    never = never_detected(result)
    caveats = [_never_detected(result, skeleton, skeleton.joints[j])
               for j in np.flatnonzero(never)]
    caveats += [_placed_in_part(result, skeleton, int(j))
                for j in np.flatnonzero(placed_by_model(result).any(axis=0) & ~never)]
    empty = empty_frames(result)
    if empty.any():
        caveats.append(f"{int(empty.sum())} of {empty.size} frames ({_runs(empty)}) observe "
                       "no point and were not filled: stored without positions")
    return tuple(caveats)
