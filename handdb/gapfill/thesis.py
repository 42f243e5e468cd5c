"""The thesis's five gap-filling methods (its section 3.7), as named baselines.

All five extrapolate causally, frame after frame, from the frames before a missing point,
and feed on their own predictions inside a gap, as the thesis's program does:

1. ``previous``: the point's value in the previous frame.
2. ``previous-diff``: the previous value plus the point's last frame-to-frame change.
3. ``interfinger``: method 2, but the change is reversed when the interfinger neighbour
   (:func:`~handdb.gapfill.dependency.interfinger_neighbours`) has just turned and the
   point was still moving the neighbour's old way. A *turn* is a rise then a fall, or a fall
   then a rise, over the neighbour's last three values. Table 3.1: A = 3, 5, 7, ?;
   B = 3, 5, 4 turns down while A rises, so A is predicted 7 - 2 = 5 (method 2: 9).
4. ``intrafinger``: method 3's rule with the joint's parent on the same finger
   (:func:`~handdb.gapfill.dependency.intrafinger_parents`).
5. ``intrafinger-rate``: the parent's last change (direction and rate) applied to the
   point's previous value.

The rules act on u and v separately. They need 1, 2 and 3 earlier frames; with fewer
(near the start of the clip) a method uses the most demanding rule its history allows, and
says so in a ``short_history`` flag. The thesis assumes a complete first frame supplied by
the user; here a joint missing from the first frame is placed there by carrying it with
the palm from its first observed frame (or from the rest pose if it is never observed).

Differences from the thesis's appendix program, which implement the text instead:

* The program tests the v axis of method 3 with the turn conditions swapped (it reverses
  when the neighbour turns *towards* the point's direction); both axes use the described
  rule here.
* The program's method 5, when a turn is detected, moves the point by the parent's change
  taken as a percentage of the parent's coordinate and re-applied to the point's own
  coordinate, which depends on where the image origin lies; here the parent's absolute
  change is used. With it both of the program's branches reduce to adding the parent's
  last change.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from handdb.gapfill.dependency import interfinger_neighbours, intrafinger_parents
from handdb.gapfill.gaps import find_gaps
from handdb.gapfill.registry import SHORT_HISTORY, GapFlag, MethodOutput
from handdb.gapfill.rigid import carry_across_gaps, palm_joints, place_from_rest_pose
from handdb.hand.skeletons import Skeleton

#: A rule predicts frame ``t`` of ``joints`` from the filled track before ``t``, given
#: the joints they depend on: ``rule(track, t, joints, dependency) -> (K, 2)``.
Rule = Callable[[np.ndarray, int, np.ndarray, np.ndarray], np.ndarray]


def previous_value(track: np.ndarray, t: int, joints: np.ndarray, _: np.ndarray) -> np.ndarray:
    """Predict by method 1: the value in frame ``t - 1``."""
    return track[t - 1, joints]


def previous_change(track: np.ndarray, t: int, joints: np.ndarray, _: np.ndarray) -> np.ndarray:
    """Predict by method 2: the last value plus the last frame-to-frame change."""
    last = track[t - 1, joints]
    return last + (last - track[t - 2, joints])


def turn_aware_change(
    track: np.ndarray, t: int, joints: np.ndarray, dependency: np.ndarray
) -> np.ndarray:
    """Predict by methods 3 and 4: method 2, reversed where the dependency turned against it.

    The change is reversed on an axis where the dependency's values at ``t - 3, t - 2,
    t - 1`` rise then fall while the point's last change rises, or fall then rise while it
    falls.
    """
    last = track[t - 1, joints]
    change = last - track[t - 2, joints]
    a, b, c = track[t - 3, dependency], track[t - 2, dependency], track[t - 1, dependency]
    turned_down = (a < b) & (b > c)
    turned_up = (a > b) & (b < c)
    reverse = (turned_down & (change > 0)) | (turned_up & (change < 0))
    return last + np.where(reverse, -change, change)


def parent_change(
    track: np.ndarray, t: int, joints: np.ndarray, dependency: np.ndarray
) -> np.ndarray:
    """Predict by method 5: the last value plus the dependency's last change."""
    return track[t - 1, joints] + (track[t - 1, dependency] - track[t - 2, dependency])


#: The rules by the number of earlier frames they need, for the fallback near the start.
RULE_BY_HISTORY: dict[int, Rule] = {1: previous_value, 2: previous_change}
#: Thesis method names: (rule, earlier frames it needs, dependency map or None).
THESIS_RULES: dict[str, tuple[Rule, int, Callable[[Skeleton], np.ndarray] | None]] = {
    "previous": (previous_value, 1, None),
    "previous-diff": (previous_change, 2, None),
    "interfinger": (turn_aware_change, 3, interfinger_neighbours),
    "intrafinger": (turn_aware_change, 3, intrafinger_parents),
    "intrafinger-rate": (parent_change, 3, intrafinger_parents),
}


def seed_first_frame(uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Complete frame 0, the thesis's premise, from the palm's motion or the rest pose.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2)``: ``uv`` with the missing points of frame 0 filled.
    """
    gaps = find_gaps(missing)
    leading = gaps.select(gaps.leading & ~gaps.whole_clip)
    carried = carry_across_gaps(uv, missing, leading, palm_joints(skeleton))
    seeded = uv.copy()
    seeded[0] = carried[0]
    never_seen = np.unique(gaps.joint[gaps.whole_clip])
    if never_seen.size:
        seeded[0] = place_from_rest_pose(seeded[:1], missing[:1], skeleton, never_seen)[0]
    return seeded


def extrapolate(
    uv: np.ndarray, missing: np.ndarray, rule: Rule, history: int, dependency: np.ndarray
) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """Fill missing points frame after frame with ``rule``, feeding on earlier predictions.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, complete in frame 0.
    missing
        ``(T, J) bool``.
    rule
        The prediction rule.
    history
        Earlier frames ``rule`` needs.
    dependency
        ``(J,) int64``: the joint each joint depends on.

    Returns
    -------
    filled
        ``(T, J, 2) float64``.
    fallbacks
        Earlier frames available -> ``(T, J) bool`` points filled with the simpler rule
        that history allows.
    """
    track = uv.copy()
    fallbacks = {n: np.zeros_like(missing) for n in range(1, history)}
    for t in map(int, np.flatnonzero(missing[1:].any(axis=1)) + 1):
        joints = np.flatnonzero(missing[t])
        if t < history:
            track[t, joints] = RULE_BY_HISTORY[t](track, t, joints, dependency[joints])
            fallbacks[t][t, joints] = True
        else:
            track[t, joints] = rule(track, t, joints, dependency[joints])
    return track, fallbacks


def thesis_method(name: str) -> Callable[..., MethodOutput]:
    """The gap-filling method of the thesis called ``name`` (a key of :data:`THESIS_RULES`)."""
    rule, history, dependency_map = THESIS_RULES[name]

    def fill(uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton) -> MethodOutput:
        dependency = (np.arange(skeleton.n_joints) if dependency_map is None
                      else dependency_map(skeleton))
        seeded = seed_first_frame(uv, missing, skeleton)
        filled, fallbacks = extrapolate(seeded, missing, rule, history, dependency)
        flags = []
        for available, mask in fallbacks.items():
            gaps = find_gaps(mask)
            flags += [
                GapFlag(skeleton.joints[j], int(a), int(b), SHORT_HISTORY,
                        f"{available} earlier frame(s), {history} needed: used "
                        f"{RULE_BY_HISTORY[available].__name__}")
                for j, a, b in zip(gaps.joint, gaps.start, gaps.stop, strict=True)
            ]
        return MethodOutput(filled, flags=tuple(flags))

    fill.__name__ = f"fill_{name.replace('-', '_')}"
    fill.__doc__ = f"The thesis's method '{name}' (see :mod:`handdb.gapfill.thesis`)."
    return fill

