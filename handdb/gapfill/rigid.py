"""Rigid-body filling: carry missing points along with the palm.

The wrist, the finger bases and the palm points move together as one nearly rigid body.
Seen orthographically, such a body moves by an affine map of the image, so a missing palm
point is placed by fitting that map from the last frame before its gap (and the first frame
after it) to the current frame, on the palm points visible in both, and carrying the
point's last (next) known position with it; the two estimates are blended across the gap.
This is the image-space counterpart of the rigid-body fill of optical motion capture. A
joint never observed is placed by fitting the rest pose to the observed joints of each frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import numpy as np

from handdb.compiled import kernel
from handdb.gapfill.gaps import Gaps, find_gaps
from handdb.gapfill.registry import MethodOutput
from handdb.gapfill.rest_pose import rest_pose_2d
from handdb.gapfill.transfer import NO_MAP, fit_map, map_points
from handdb.hand.skeletons import Skeleton

#: Roles of the joints that move with the palm.
PALM_ROLES = frozenset({"wrist", "palm_fold", "palm_center", "cmc", "mcp"})

#: Fewest palm points a frame needs before the rest pose is fitted to them alone.
MIN_PALM_POINTS = 3

#: Smallest area scale of a carry weighed in the mean of :func:`_edge_point` (guards the
#: inverse of a degenerate map).
MIN_AREA_SCALE = 1e-12


def palm_joints(skeleton: Skeleton) -> np.ndarray:
    """``(J,) bool``: joints that move with the palm (wrist, palm points, finger bases).

    The thumb's MCP is left out: the thumb's base bone swings on its own. The array is
    shared between calls: read-only.
    """
    return _palm_joints(skeleton.roles, skeleton.fingers)


@cache
def _palm_joints(roles: tuple[str, ...], fingers: tuple[str, ...]) -> np.ndarray:
    role, finger = np.asarray(roles), np.asarray(fingers)
    palm = np.isin(role, list(PALM_ROLES)) & ~((finger == "thumb") & (role == "mcp"))
    palm.flags.writeable = False
    return palm


def _carriers_of(basis: np.ndarray, joint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each point's carrier joints: ``(N, K) int64`` indices and ``(N, K) bool`` validity.

    ``basis`` is ``(J, J) bool`` (row ``j``: the joints that carry joint ``j``); ``K`` is the
    most carriers any of the points has, rows with fewer are padded with invalid entries.
    """
    rows = basis & ~np.eye(basis.shape[0], dtype=bool)
    width = max(int(rows.sum(axis=1)[joint].max(initial=0)), 1)
    carriers = np.argsort(~rows, axis=1, kind="stable")[:, :width]
    return carriers[joint], np.take_along_axis(rows, carriers, axis=1)[joint]


def carried_points(
    problems: Sequence[tuple[np.ndarray, np.ndarray, Gaps]], basis: np.ndarray,
    affine: bool = True,
) -> list[np.ndarray]:
    """Carry the points of gaps from both edges of each gap, and blend.

    Parameters
    ----------
    problems
        ``(uv, missing, gaps)`` triples: tracks ``(T, J, 2)``, the points not to carry
        with ``(T, J) bool``, and the gaps whose points to carry. Every problem's maps are
        fitted in one batch.
    basis
        ``(J,) bool`` or ``(J, J) bool``: as for :func:`carry_across_gaps`.
    affine
        Fit affine maps (else similarities).

    Returns
    -------
    list of numpy.ndarray
        Per problem, ``(N, 2) float64``: the points of ``gaps.frames()``, in order.
    """
    n_joints = problems[0][0].shape[1]
    basis = np.broadcast_to(basis, (n_joints, n_joints))
    points = [gaps.frames() for _, _, gaps in problems]
    edges = [(np.maximum(gaps.start[gap] - 1, 0), np.minimum(gaps.stop[gap], gaps.n_frames - 1))
             for (_, _, gaps), (gap, _, _) in zip(problems, points, strict=True)]
    sizes = [2 * gap.size for gap, _, _ in points]
    carriers, valid = (np.split(part, np.cumsum(sizes)[:-1]) for part in _carriers_of(
        basis, np.concatenate([np.tile(joint, 2) for _, _, joint in points])))
    fits = []
    for (uv, missing, _), (_, frame, joint), (before, after), by, ok in zip(
            problems, points, edges, carriers, valid, strict=True):
        reference, now = np.concatenate([before, after]), np.tile(frame, 2)
        weights = ok & ~missing[reference[:, None], by] & ~missing[now[:, None], by]
        fits.append((uv[reference[:, None], by], uv[now[:, None], by], weights,
                     uv[reference, np.tile(joint, 2)]))
    source, target, weights, query = (np.concatenate(part) for part in zip(*fits, strict=True))
    mapped, ok = map_points(source, target, weights, query, affine=affine)
    carried = np.split(np.where(ok[:, None], mapped, query), np.cumsum(sizes)[:-1])
    blended = []
    for (_, _, gaps), (gap, frame, _), (before, after), both in zip(
            problems, points, edges, carried, strict=True):
        from_before, from_after = np.split(both, 2)
        share_after = ((frame - before) / np.maximum(after - before, 1))[:, None]
        blend = (1 - share_after) * from_before + share_after * from_after
        blend = np.where(gaps.leading[gap][:, None], from_after, blend)
        blended.append(np.where(gaps.trailing[gap][:, None], from_before, blend))
    return blended


def carry_across_gaps(
    uv: np.ndarray, missing: np.ndarray, gaps: Gaps, basis: np.ndarray, *, affine: bool = True
) -> np.ndarray:
    """Fill the points of non-whole-clip ``gaps`` by carrying them with the ``basis`` joints.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, NaN where missing.
    missing
        ``(T, J) bool``.
    gaps
        The gaps to fill; each must have an observed frame before or after it.
    basis
        ``(J,) bool``: the joints whose motion carries the missing points; or
        ``(J, J) bool``: row ``j``, the joints that carry joint ``j``.
    affine
        Fit affine maps (else similarities).

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``uv`` with the gaps' points filled.
    """
    _, frame, joint = gaps.frames()
    filled = uv.copy()
    filled[frame, joint] = carried_points([(uv, missing, gaps)], basis, affine)[0]
    return filled


def placeable_frames(missing: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """``(T,) bool``: the frames that show enough of the palm to place the rest pose on.

    A frame observing :data:`MIN_PALM_POINTS` palm points (:func:`palm_joints`) gives the
    rest pose's palm an affine map into the image; fewer, or finger points alone (which
    bend away from the rest pose), give no hand to place a never-observed joint on.

    Parameters
    ----------
    missing
        ``(T, J) bool``: points not observed.
    skeleton
        Skeleton of ``missing``'s joint axis.
    """
    return (~missing & palm_joints(skeleton)).sum(axis=1) >= MIN_PALM_POINTS


def place_from_rest_pose(
    uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, joints: np.ndarray
) -> np.ndarray:
    """Place never-observed ``joints`` by fitting the rest pose to each frame's hand.

    In each of the :func:`placeable_frames` the rest pose is fitted to every joint the
    frame observes, so a fingertip is placed from its own finger's joints as well as the
    palm (how far off that leaves it, real and synthetic: ``benchmarks/RESULTS-gapfill.md``).
    The other frames are left to the caller.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    missing
        ``(T, J) bool``: points not observed.
    skeleton
        Skeleton of ``uv``.
    joints
        ``(K,) int64``: the joints never observed.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``uv`` with ``joints`` placed in the placeable frames, NaN
        in the others.
    """
    frames = np.flatnonzero(placeable_frames(missing, skeleton))
    frame = np.repeat(frames, joints.size)
    joint = np.tile(joints, frames.size)
    rest = rest_pose_2d(skeleton)
    weights = ~missing[frame]
    source = np.broadcast_to(rest, (frame.size, *rest.shape))
    mapped, _ = map_points(source, uv[frame], weights, rest[joint])
    filled = uv.copy()
    filled[:, joints] = np.nan
    filled[frame, joint] = mapped
    return filled


def place_on_chords(
    uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, joints: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Place never-observed ``joints`` between their observed parent and only child.

    An annotation that skips a joint of a chain (three points per finger: a DIP never
    marked between the PIP and the tip) still gives the two points around it; the joint
    lies near the chord joining them, dividing it as the rest pose divides its two
    bones. The image cannot show how the finger bends there: the lifting meets both bone
    lengths in depth.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    missing
        ``(T, J) bool``: points not observed.
    skeleton
        Skeleton of ``uv``.
    joints
        Joints never observed, indices.

    Returns
    -------
    filled
        ``(T, J, 2) float64``: ``uv`` with the joints placed where their neighbours are
        observed.
    placed
        ``(T, J) bool``: the points placed.
    """
    rest = rest_pose_2d(skeleton)
    filled, placed = uv.copy(), np.zeros(missing.shape, dtype=bool)
    for joint in joints:
        parent, children = skeleton.parents[joint], skeleton.children(joint)
        if parent < 0 or len(children) != 1:
            continue
        child = children[0]
        first = np.linalg.norm(rest[joint] - rest[parent])
        second = np.linalg.norm(rest[child] - rest[joint])
        both = ~missing[:, parent] & ~missing[:, child]
        filled[both, joint] = uv[both, parent] + (first / (first + second)) * (
            uv[both, child] - uv[both, parent])
        placed[both, joint] = True
    return filled, placed


def fill_rigid(
    uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, *, affine: bool = True
) -> MethodOutput:
    """Fill every gap by carrying the point with the palm (a rigid-body fill).

    Exact for points that move rigidly with the palm; fingers that bend during a gap
    are only carried along with the hand.
    """
    gaps = find_gaps(missing)
    basis = palm_joints(skeleton)
    filled = carry_across_gaps(uv, missing, gaps.select(~gaps.whole_clip), basis, affine=affine)
    never_seen = np.unique(gaps.joint[gaps.whole_clip])
    if never_seen.size:
        filled = place_from_rest_pose(filled, missing, skeleton, never_seen)
    return MethodOutput(filled)


def parent_bones(skeleton: Skeleton) -> np.ndarray:
    """``(J, J) bool``: row ``j``, the joints that carry joint ``j`` along its parent bone.

    Those are its parent and grandparent; the palm joints for a joint hanging from the root
    (its parent bone is the palm); none for the root. The array is shared between calls:
    read-only.
    """
    return _parent_bones(tuple(skeleton.parents), palm_joints(skeleton).tobytes())


@cache
def _parent_bones(parents: tuple[int, ...], palm: bytes) -> np.ndarray:
    carriers = np.zeros((len(parents), len(parents)), dtype=bool)
    for joint, parent in enumerate(parents):
        if parent < 0:
            continue
        grandparent = parents[parent]
        if grandparent < 0:
            carriers[joint] = np.frombuffer(palm, dtype=bool)
        else:
            carriers[joint, [parent, grandparent]] = True
    carriers.flags.writeable = False
    return carriers


def carry_along_chains(
    uv: np.ndarray, missing: np.ndarray, gaps: Gaps, skeleton: Skeleton
) -> np.ndarray:
    """Fill finger gaps by carrying each point with its parent bone.

    The bone from a joint's grandparent to its parent moves (in the image) by a similarity;
    applied to the joint's last known position before the gap and its first after it, and
    blended across the gap, it keeps the joint's angle to its parent bone changing
    linearly through the gap. Joints are filled one depth at a time from the root outward,
    so a joint's parent bone is complete (observed or already filled) when the joint is
    filled.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels; the joints of the palm and every gap not in
        ``gaps`` must already be filled.
    missing
        ``(T, J) bool``: the points that were missing.
    gaps
        Non-whole-clip gaps of joints that have a parent (a joint hanging from the root is
        carried with the palm instead).
    skeleton
        The clip's skeleton.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``uv`` with ``gaps`` filled.
    """
    return carry_along_chains_many(uv, [(missing, gaps)], skeleton)[0]


def carry_along_chains_many(
    uv: np.ndarray, problems: Sequence[tuple[np.ndarray, Gaps]], skeleton: Skeleton,
    reach: Sequence[np.ndarray] | None = None,
) -> list[np.ndarray]:
    """:func:`carry_along_chains` for several ``(missing, gaps)`` problems on one clip.

    Each problem fills its own copy of ``uv`` (:func:`_carry_chains`, compiled).

    Parameters
    ----------
    uv, problems, skeleton
        As for :func:`carry_along_chains`, one ``(missing, gaps)`` pair per problem.
    reach
        Per problem, ``(G,) int64``: how many observed frames at each edge of each gap the
        point is carried from (:func:`_carry_chains`); 1 (the edge frame alone) if not
        given.

    Returns
    -------
    list of numpy.ndarray
        Per problem, ``(T, J, 2) float64``: ``uv`` with its gaps filled.
    """
    carriers = parent_bones(skeleton)
    depth = skeleton.depth()
    filled = []
    for index, (missing, gaps) in enumerate(problems):
        frames = (np.ones(len(gaps), dtype=np.int64) if reach is None
                  else np.asarray(reach[index], dtype=np.int64))
        filled.append(uv.copy())
        _carry_chains(filled[-1], ~missing, gaps.joint, gaps.start, gaps.stop,
                      depth[gaps.joint], frames, carriers)
    return filled


@kernel
def _carry_chains(
    state: np.ndarray, observed: np.ndarray, joint: np.ndarray, start: np.ndarray,
    stop: np.ndarray, depth: np.ndarray, reach: np.ndarray, carriers: np.ndarray,
) -> None:
    """Fill gaps in place, a depth at a time, carrying each point with its carriers.

    Parameters
    ----------
    state
        ``(T, J, 2) float64``, pixels: the tracks, every point outside the gaps filled;
        the gaps' points are written.
    observed
        ``(T, J) bool``: the points observed (a gap's point is carried only from those).
    joint, start, stop
        ``(G,) int64``: the gaps (as :class:`~handdb.gapfill.gaps.Gaps`), none whole-clip.
    depth
        ``(G,) int64``: the depth of each gap's joint; shallower gaps are filled first.
    reach
        ``(G,) int64``: the observed frames at each edge of each gap the point is carried
        from, at least 1.
    carriers
        ``(J, J) bool``: row ``j``, the joints that carry joint ``j`` (:func:`parent_bones`).

    Notes
    -----
    Each point is carried from the frame before its gap and from the frame after it by
    the similarity fitted to its carriers seen (not in a gap still to fill) in both frames
    (:func:`_carry_point`), and the two are blended linearly across the gap; a leading
    gap takes the estimate from after it, a trailing gap the one from before it. The point
    carried from an edge frame is the mean of the point in the ``reach`` observed frames
    of the run beside the gap, each carried to the edge frame: detector noise in one edge
    sample would be held across the whole gap, the mean of several carries less of it.
    """
    n_frames = state.shape[0]
    unresolved = np.zeros(state.shape[:2], dtype=np.bool_)
    for g in range(joint.size):
        unresolved[start[g]:stop[g], joint[g]] = True
    order = np.argsort(depth, kind="mergesort")
    carried = np.empty((n_frames, 2))
    weights = np.empty(carriers.shape[1], dtype=np.bool_)
    first = 0
    while first < order.size:
        last = first
        while last < order.size and depth[order[last]] == depth[order[first]]:
            last += 1
        level = order[first:last]
        longest = 0
        for g in level:
            longest = max(longest, stop[g] - start[g])
        values = np.empty((level.size, longest, 2))
        for index, g in enumerate(level):
            before, after = max(start[g] - 1, 0), min(stop[g], n_frames - 1)
            bx, by = _edge_point(state, observed, unresolved, carriers[joint[g]], joint[g],
                                 before, -1, reach[g], weights)
            ax, ay = _edge_point(state, observed, unresolved, carriers[joint[g]], joint[g],
                                 after, 1, reach[g], weights)
            for frame in range(start[g], stop[g]):
                x0, y0 = _carry_point(state, unresolved, carriers[joint[g]], joint[g],
                                      before, frame, weights, bx, by)
                x1, y1 = _carry_point(state, unresolved, carriers[joint[g]], joint[g],
                                      after, frame, weights, ax, ay)
                share = (frame - before) / max(after - before, 1)
                if start[g] == 0:
                    carried[frame] = x1, y1
                elif stop[g] == n_frames:
                    carried[frame] = x0, y0
                else:
                    carried[frame] = ((1 - share) * x0 + share * x1,
                                      (1 - share) * y0 + share * y1)
            values[index, :stop[g] - start[g]] = carried[start[g]:stop[g]]
        for index, g in enumerate(level):
            state[start[g]:stop[g], joint[g]] = values[index, :stop[g] - start[g]]
            unresolved[start[g]:stop[g], joint[g]] = False
        first = last


@kernel
def _edge_point(
    state: np.ndarray, observed: np.ndarray, unresolved: np.ndarray, carrier: np.ndarray,
    joint: int, edge: int, step: int, reach: int, weights: np.ndarray,
) -> tuple[float, float]:
    """The joint's point at a gap's edge frame, from up to ``reach`` frames of its run.

    The frames ``edge, edge + step, ...`` where the joint is observed, up to ``reach`` of
    them and not past the run, are each carried to ``edge`` (:func:`_carry_point`) and
    averaged.

    Parameters
    ----------
    state, observed, unresolved, carrier, joint, weights
        As for :func:`_carry_chains` and :func:`_carry_point`.
    edge
        The frame next to the gap.
    step
        -1 to read the frames before ``edge``, 1 the frames after it.
    reach
        Most frames averaged, at least 1.

    Returns
    -------
    x, y
        Pixels; the point at ``edge`` when it is not observed or ``reach`` is 1.
    """
    x, y = state[edge, joint, 0], state[edge, joint, 1]
    if reach <= 1 or not observed[edge, joint]:
        return x, y
    n_frames = state.shape[0]
    total, count = 1.0, 1
    frame = edge + step
    while count < reach and 0 <= frame < n_frames and observed[frame, joint]:
        (a, b, c, d, offset_x, offset_y), kind = _carrier_map(
            state, unresolved, carrier, joint, frame, edge, weights)
        if kind != NO_MAP:
            # A carry that magnifies (the carrier bone foreshortened in ``frame``)
            # magnifies the noise of the point it carries: weighed by its inverse area.
            weight = 1.0 / max(abs(a * d - b * c), MIN_AREA_SCALE)
            px, py = state[frame, joint, 0], state[frame, joint, 1]
            x += weight * (a * px + b * py + offset_x)
            y += weight * (c * px + d * py + offset_y)
            total += weight
        count += 1
        frame += step
    return x / total, y / total


@kernel
def _carrier_map(
    state: np.ndarray, unresolved: np.ndarray, carrier: np.ndarray, joint: int,
    reference: int, now: int, weights: np.ndarray,
) -> tuple[tuple[float, float, float, float, float, float], int]:
    """The similarity carrying ``joint`` from frame ``reference`` to frame ``now``.

    Fitted over the joint's carriers resolved in both frames
    (:func:`~handdb.gapfill.transfer.fit_map` with ``affine=False``); the parameters are
    those of :func:`_carry_point`. Returns the map and its kind.
    """
    for k in range(carrier.size):
        weights[k] = (carrier[k] and k != joint and not unresolved[reference, k]
                      and not unresolved[now, k])
    return fit_map(state[reference], state[now], weights, False)


@kernel
def _carry_point(
    state: np.ndarray, unresolved: np.ndarray, carrier: np.ndarray, joint: int,
    reference: int, now: int, weights: np.ndarray, query_x: float, query_y: float,
) -> tuple[float, float]:
    """Carry a point from frame ``reference`` to frame ``now`` with the joint's carriers.

    The similarity from the carriers' points at ``reference`` to those at ``now``, fitted
    over the carriers resolved in both frames (:func:`~handdb.gapfill.transfer.fit_maps`
    with ``affine=False``), is applied to the point ``(query_x, query_y)`` (the joint's,
    or an estimate of it, at ``reference``).

    Parameters
    ----------
    state
        ``(T, J, 2) float64``, pixels.
    unresolved
        ``(T, J) bool``: points not filled yet, never carriers.
    carrier
        ``(J,) bool``: the joints that carry ``joint``.
    joint, reference, now
        The joint and the two frames.
    weights
        ``(J,) bool``: scratch space, overwritten.
    query_x, query_y
        The point carried, pixels.

    Returns
    -------
    x, y
        The carried point, pixels; the query itself if no carrier is resolved in both
        frames.
    """
    (a, b, c, d, offset_x, offset_y), kind = _carrier_map(state, unresolved, carrier, joint,
                                                          reference, now, weights)
    if kind == NO_MAP:
        return query_x, query_y
    return a * query_x + b * query_y + offset_x, c * query_x + d * query_y + offset_y
