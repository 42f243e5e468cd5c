"""The default lifting method, ``kinematic``: depth signs settled with what hands can do.

A detector's points jitter, and the depth of a bone lying nearly in the image plane is the
square root of a small difference of its length and its image, so a pixel of jitter turns
into millimetres of depth and flips signs. The tracks are therefore first smoothed in time
where they jitter (:func:`handdb.denoise.denoise`: a Savitzky-Golay window chosen
by Stein's risk on the clip's own measured noise, none on clean tracks or lone images), and
the result's ``x, y`` follow the smoothed points.

Per frame, the unsigned depth of every bone follows from eq. 5 at a robust, smoothed scale:
the second-largest ratio of image to bone length (one outlier bone allowed), then an upper
percentile over a window of frames (:func:`handdb.lifting.temporal.smooth_scale`). The
signs are then chosen in four steps:

1. **Rigid palm.** The palm without the thumb (the root, a palm centre, the long fingers'
   MCP joints) is near rigid. When the clip's views determine it, its 3D shape is
   recovered from the track and fitted to every frame in its two poses, tilted either way
   (:mod:`handdb.lifting.palm_template`); the frame's scale becomes the pose's. Otherwise
   (short or still clips, pinhole cameras) each frame's palm is the sign pattern of its
   bones that best fits a plane, and its mirror image (:mod:`handdb.lifting.palm_states`).
2. **Thumb base.** The thumb's carpometacarpal joint lies off that palm, by an amount that
   differs between hands and annotations; its height is one unknown of the clip,
   estimated from every frame's two candidate heights (:mod:`handdb.lifting.thumb_base`).
3. **Fingers.** Under each palm state, each finger's three bones below the palm take one
   of eight sign states, scored by the hand prior (:mod:`handdb.lifting.hand_prior`):
   ranges of motion, flexion toward the palm, the DIP about 2/3 of the PIP.
4. **Time.** Signed depths move smoothly: the palm's tilt, the thumb base's sign and every
   bone's sign are chains over the frames under a constant-velocity prior
   (:mod:`handdb.lifting.temporal`). The tilt's evidence is the palm's own fit and the
   fingers' likelihood under each tilt, each finger's say capped
   (:data:`~handdb.lifting.settle.FINGER_VOTE_CAP`); see :mod:`handdb.lifting.settle`.

The confidence of each bone's sign is its posterior, discounted by the probability that
the whole clip is mirrored: flipping every sign at once changes only the
flexion-direction evidence and the thumb base's side, so a clip without clear flexion (a
flat hand) cannot settle it, and the result says so (``mirror_ambiguous``). A recovered
template comes in two mirror-image chiralities; both are solved and compared. The odds of
either comparison count each source's frames once per independent frame
(:mod:`handdb.lifting.evidence`): a hand holding one pose is one piece of evidence.

With a pinhole camera the root's depth comes from the bone lengths and the rays
(:func:`handdb.lifting.pinhole.estimate_root_depth`), then every joint is placed on its ray
and the hand prior chooses among the two solutions of every bone.

Its accuracy, on real captures and synthetic hands, is in ``benchmarks/RESULTS-real.md``
and ``benchmarks/RESULTS-lifting.md``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from handdb.clip import Camera, finite_points
from handdb.denoise import denoise
from handdb.hand.layout import HandLayout
from handdb.hand.skeletons import Skeleton
from handdb.lifting.finger_geometry import FingerCandidates, perspective_candidates
from handdb.lifting.geometry import (
    accumulate_depths,
    centred_pixels,
    depth_magnitudes,
    eq6_scale,
    orthographic_points,
    projected_lengths,
)
from handdb.lifting.hand_prior import HANDEDNESS, score_fingers, score_mirrored_fingers
from handdb.lifting.palm_states import (
    PalmParts,
    PalmStates,
    arch_heights,
    arch_log_likelihood,
    palm_parts,
    plane_states,
    ray_plane_states,
    template_states,
)
from handdb.lifting.pinhole import camera_rays, estimate_root_depth, ray_roots
from handdb.lifting.result import LiftResult
from handdb.lifting.settle import (
    TEMPORAL_FLOOR,
    VOTE_FIELDS,
    Case,
    Settled,
    Votes,
    chosen_votes,
    finger_signs,
    mirror_evidence,
    pick_states,
    settle,
    votes_of,
)
from handdb.lifting.temporal import sigmoid, smooth_scale
from handdb.lifting.thumb_base import plane_heights

#: The scale of a frame lets its most stretched bone be an outlier (see
#: :func:`handdb.lifting.geometry.eq6_scale`): trackers' bones vary in length.
SCALE_RANK = 2

#: The clip-wide mirror counts as settled when it is this many times less likely.
MIRROR_SETTLED_ODDS = 20.0

#: Bounds of a sign's confidence: a probability that the chosen sign is right.
MIN_CONFIDENCE, MAX_CONFIDENCE = 0.5, 1.0

#: The mirror image through the image plane, ``z -> -z``.
MIRROR = np.array([1.0, 1.0, -1.0])

#: Frames whose perspective candidates are built and scored at once: the candidates take
#: about 4 kB a frame, so a long clip's in one piece would be hundreds of MB of fresh
#: memory, each page faulted in, where blocks of this many frames reuse a few MB.
CANDIDATE_BLOCK_FRAMES = 4096

#: The perspective candidates of the frames ``start:stop`` of a clip.
CandidateBlock = Callable[[int, int], FingerCandidates]


@dataclass(frozen=True)
class Hypotheses:
    """A :class:`~handdb.lifting.settle.Case` with the positions its choices stand for.

    Attributes
    ----------
    case
        The hypotheses the signs are chosen among.
    palm
        ``(T, 2, J, 3) float64``, clip units: the rigid palm's joints in each state.
    thumb
        ``(2, T, 2, 3) float64``: the thumb base per sign and state; ``None`` without one.
    """

    case: Case
    palm: np.ndarray
    thumb: np.ndarray | None


@dataclass(frozen=True)
class Solution:
    """The chosen hypotheses and signs of a clip.

    Attributes
    ----------
    hypotheses
        The case chosen.
    settled
        Its tilt and thumb base.
    finger_odds
        ``(T, F, 3) float64``: posterior log-odds of each finger bone's positive sign.
    mirror_log_odds
        Log-odds of the solution against its clip-wide mirror, counting the clip's frames
        once per independent frame; below 0 where the plain sum chose against them.
    """

    hypotheses: Hypotheses
    settled: Settled
    finger_odds: np.ndarray
    mirror_log_odds: float


def thumb_only(layout: HandLayout) -> HandLayout:
    """The layout with the thumb (its finger 0) as its only finger."""
    return dataclasses.replace(layout, fingers=layout.fingers[:1], chains=layout.chains[:1],
                               chain_bases=layout.chain_bases[:1])


def palm_size(skeleton: Skeleton, bone_lengths: np.ndarray) -> float:
    """The palm length thumb heights are measured in: the bone ending at the middle MCP."""
    return float(bone_lengths[skeleton.index("middle_mcp")])


def _floors(parts: PalmParts, bone_lengths: np.ndarray) -> tuple[float, float]:
    """Smallest spreads of the palm's and the thumb base's depth changes, clip units."""
    palm = TEMPORAL_FLOOR * float(np.mean(bone_lengths[parts.bones]))
    thumb = TEMPORAL_FLOOR * float(bone_lengths[parts.thumb_base]) if parts.thumb_base >= 0 \
        else palm
    return palm, thumb


def _split(full: Votes, thumb: Votes | None) -> tuple[Votes, tuple[Votes, Votes]]:
    """The other fingers' votes, and the thumb's per base sign, from a pass and its partner.

    ``full`` is a pass over every finger whose thumb base lies on sign 0 in palm state 0
    and, state 1 being its mirror image, on sign 1 in state 1; ``thumb`` the thumb-only
    pass with the base on the other side (``None`` without a thumb base of its own).
    """
    own = full.fingers(slice(0, 1))
    if thumb is None:
        return full.fingers(slice(1, None)), (own, own)
    return full.fingers(slice(1, None)), (pick_states(own, thumb), pick_states(thumb, own))


def _orthographic_votes(xy: np.ndarray, abs_dz: np.ndarray, palm_z: np.ndarray,
                        thumb_z: np.ndarray | None, bone_lengths: np.ndarray,
                        parts: PalmParts, hand: str) -> tuple[Votes, tuple[Votes, Votes]]:
    """The hand prior's votes of a palm (state 0) and its mirror image (state 1).

    ``palm_z`` ``(T, J)`` is the palm's depth in state 0; ``thumb_z`` ``(2, T)`` the
    thumb base's under each sign there (``None`` without a thumb base). One pass scores
    every finger with the base on sign 0; a thumb-only pass puts it on sign 1.
    """
    if thumb_z is None:
        return _split(votes_of(score_mirrored_fingers(xy, abs_dz, palm_z, bone_lengths,
                                                      parts.layout, hand)), None)
    depth = [palm_z.copy(), palm_z.copy()]
    for sign in range(2):
        depth[sign][:, parts.thumb_base] = thumb_z[sign]
    full = votes_of(score_mirrored_fingers(xy, abs_dz, depth[0], bone_lengths, parts.layout,
                                           hand))
    thumb = votes_of(score_mirrored_fingers(xy, abs_dz, depth[1], bone_lengths,
                                            thumb_only(parts.layout), hand))
    return _split(full, thumb)


def _orthographic_thumb(palm: np.ndarray, xy: np.ndarray, abs_dz: np.ndarray,
                        skeleton: Skeleton, parts: PalmParts) -> np.ndarray:
    """The thumb base under either sign of its bone in each palm state, ``(2, T, 2, 3)``."""
    base = parts.thumb_base
    options = np.empty((2, len(xy), 2, 3))
    options[..., :2] = (xy[:, base] - xy[:, skeleton.root])[None, :, None]
    for sign, direction in enumerate((1.0, -1.0)):
        options[sign, ..., 2] = palm[:, :, parts.thumb_parent, 2] + direction * abs_dz[:, base,
                                                                                     None]
    return options


def _geometry(palm: np.ndarray, thumb: np.ndarray | None, parts: PalmParts, hand: str,
              size: float) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The thumb base's depth on its parent and height over the palm plane, ``(2, T, 2)``.

    Heights in palm lengths (``size``, clip units); ``(None, None)`` without a thumb base.
    """
    if thumb is None:
        return None, None
    heights = plane_heights(palm[:, :, parts.joints], thumb, parts.corners, HANDEDNESS[hand])
    return thumb[..., 2] - palm[None, :, :, parts.thumb_parent, 2], heights / size


def _orthographic_hypotheses(states: PalmStates, xy: np.ndarray, abs_dz: np.ndarray,
                             skeleton: Skeleton, parts: PalmParts, bone_lengths: np.ndarray,
                             hand: str) -> list[Hypotheses]:
    """The cases of orthographic palm states: one if mirrored, else both chiralities.

    The hand prior scores the palm of state 0 and its mirror image in one pass
    (:func:`~handdb.lifting.hand_prior.score_mirrored_fingers`). For a plane fit the
    mirror image is state 1. A template's state 1 is the other pose of a shape that is
    not quite planar, close to the mirror image, which stands for it in the fingers'
    votes; the template's mirror image (every depth flipped, the other chirality) is a
    second case, whose states are exactly the first's mirrored.
    """
    palm, size = states.points, palm_size(skeleton, bone_lengths)
    thumb = _orthographic_thumb(palm, xy, abs_dz, skeleton, parts) \
        if parts.thumb_base >= 0 else None
    others, thumb_votes = _orthographic_votes(
        xy, abs_dz, palm[:, 0, :, 2], None if thumb is None else thumb[:, :, 0, 2],
        bone_lengths, parts, hand)
    thumb_dz, heights = _geometry(palm, thumb, parts, hand, size)
    depth = palm[:, :, parts.joints, 2]
    shape = (0.0, 0.0) if states.template is None else tuple(
        float(arch_log_likelihood(arch_heights(states.template * flip, parts, hand, size)))
        for flip in (1.0, MIRROR))
    first = Hypotheses(Case(depth=depth, evidence=states.evidence, others=others,
                            thumb=thumb_votes, thumb_dz=thumb_dz, heights=heights,
                            mirrored=states.mirrored, shape_log_likelihood=shape[0]),
                       palm, thumb)
    if states.mirrored:
        return [first]
    mirror = Case(depth=-depth, evidence=states.evidence, others=others.swapped(),
                  thumb=(thumb_votes[0].swapped(), thumb_votes[1].swapped()),
                  thumb_dz=None if thumb_dz is None else -thumb_dz[::-1],
                  heights=None if heights is None else -heights[::-1], mirrored=False,
                  shape_log_likelihood=shape[1])
    return [first, Hypotheses(mirror, palm * MIRROR,
                              None if thumb is None else thumb[::-1] * MIRROR)]


def _perspective_votes(rays: np.ndarray, palm: Callable[[int, int], np.ndarray],
                       bone_lengths: np.ndarray, layout: HandLayout, hand: str) -> Votes:
    """The hand prior's votes on the fingers of ``layout`` through a pinhole.

    :func:`~handdb.lifting.hand_prior.score_fingers` of the
    :func:`~handdb.lifting.finger_geometry.perspective_candidates` of ``rays`` ``(T, J, 3)``
    and the palm, frame by frame as they are, built in blocks of
    :data:`CANDIDATE_BLOCK_FRAMES` frames; ``palm(start, stop)`` gives the block's palm
    ``(stop - start, 2, J, 3)``, clip units.
    """
    blocks = [votes_of(score_fingers(perspective_candidates(rays[start:stop], palm(start, stop),
                                                            bone_lengths, layout),
                                     bone_lengths, layout, hand))
              for start, stop in _blocks(len(rays))]
    if len(blocks) == 1:
        return blocks[0]
    return Votes(*(np.concatenate([getattr(block, name) for block in blocks])
                   for name in VOTE_FIELDS))


def _blocks(n_frames: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of consecutive blocks of :data:`CANDIDATE_BLOCK_FRAMES` frames."""
    starts = range(0, max(n_frames, 1), CANDIDATE_BLOCK_FRAMES)
    return [(start, min(start + CANDIDATE_BLOCK_FRAMES, n_frames)) for start in starts]


def _pinhole_hypotheses(states: PalmStates, rays: np.ndarray, skeleton: Skeleton,
                        parts: PalmParts, bone_lengths: np.ndarray, hand: str) -> Hypotheses:
    """The case of palm states on the rays: the thumb base at its far or near solution.

    As orthographically, one pass scores every finger with the base far in state 0 and
    near in state 1 (the state's counterpart), a thumb-only pass the other way round.
    """
    palm, layout = states.points, parts.layout
    depth = palm[:, :, parts.joints, 2] - palm[:, :, skeleton.root, None, 2]
    if parts.thumb_base < 0:
        votes = _perspective_votes(rays, lambda start, stop: palm[start:stop], bone_lengths,
                                   layout, hand)
        others, thumb_votes = _split(votes, None)
        return Hypotheses(Case(depth=depth, evidence=states.evidence, others=others,
                               thumb=thumb_votes, thumb_dz=None, heights=None, mirrored=True),
                          palm, None)
    base = parts.thumb_base
    far, near, _ = ray_roots(palm[:, :, parts.thumb_parent], rays[:, None, base],
                             bone_lengths[base])
    thumb = np.stack([far, near])                                        # (2, T, 2, 3)

    def apart(start: int, stop: int) -> np.ndarray:
        return _with_thumb(palm[start:stop], thumb[:, start:stop], np.array([0, 1]), base)

    def crossed(start: int, stop: int) -> np.ndarray:
        return _with_thumb(palm[start:stop], thumb[:, start:stop], np.array([1, 0]), base)

    alone = thumb_only(layout)
    full = _perspective_votes(rays, apart, bone_lengths, layout, hand)
    other = _perspective_votes(rays, crossed, bone_lengths, alone, hand)
    others, thumb_votes = _split(full, other)
    thumb_dz, heights = _geometry(palm, thumb, parts, hand, palm_size(skeleton, bone_lengths))
    return Hypotheses(Case(depth=depth, evidence=states.evidence, others=others,
                           thumb=thumb_votes, thumb_dz=thumb_dz, heights=heights,
                           mirrored=True), palm, thumb)


def _with_thumb(palm: np.ndarray, thumb: np.ndarray, sign: np.ndarray,
                base: int) -> np.ndarray:
    """``palm`` ``(T, 2, J, 3)`` with the thumb base of ``thumb`` ``(2, T, 2, 3)``.

    ``sign`` gives its sign per palm state, ``(2,)`` for all frames or ``(T, 2)``.
    """
    out = palm.copy()
    frames, states = np.indices(palm.shape[:2])
    out[:, :, base] = thumb[np.broadcast_to(sign, palm.shape[:2]), frames, states]
    return out


def _flipped(settled: Settled) -> Settled:
    """The clip-wide mirror image of a solution on mirrored palm states."""
    frames = np.arange(len(settled.state))
    state = 1 - settled.state
    sign = settled.thumb_sign.copy()
    sign[frames, state] = 1 - settled.thumb_sign[frames, settled.state]
    return dataclasses.replace(settled, state=state, tilt_log_odds=-settled.tilt_log_odds,
                               thumb_sign=sign, thumb_log_odds=-settled.thumb_log_odds,
                               height=-settled.height)


def _choose(hypotheses: list[Hypotheses], parts: PalmParts,
            bone_lengths: np.ndarray) -> tuple[Hypotheses, Settled, float]:
    """Settle every case and keep the best, with its log-odds against the mirror.

    A case of mirrored states is weighed against its own mirror image
    (:func:`~handdb.lifting.settle.mirror_evidence`) and flipped when that is likelier;
    the two chiralities of a template are each other's mirror images. The log-odds
    returned count the clip's frames once per independent frame
    (:meth:`~handdb.lifting.evidence.Evidence.calibrated`).
    """
    palm_floor, thumb_floor = _floors(parts, bone_lengths)
    solved = []
    for hyp in hypotheses:
        settled = settle(hyp.case, palm_floor, thumb_floor)
        odds = np.nan
        if hyp.case.mirrored:
            gap = mirror_evidence(hyp.case, settled)
            if gap.total() < 0:
                settled = dataclasses.replace(_flipped(settled),
                                              evidence=settled.evidence - gap)
                gap = -gap
            odds = gap.calibrated()
        solved.append((hyp, settled, odds))
    best = max(range(len(solved)), key=lambda i: solved[i][1].score)
    hyp, settled, odds = solved[best]
    if not hyp.case.mirrored:
        runner_up = max((s for i, (_, s, _) in enumerate(solved) if i != best),
                        key=lambda s: s.score)
        odds = (settled.evidence - runner_up.evidence).calibrated()
    return hyp, settled, float(odds)


def _chain_depths(candidates: FingerCandidates | None, state: np.ndarray, best: np.ndarray,
                  abs_dz: np.ndarray, layout: HandLayout) -> np.ndarray:
    """Depth each finger bone spans under either sign, ``(T, F * 3, 2, 1)``.

    Bones above it take their signs from the frame's most likely state ``best`` ``(T, F)``
    under the chosen palm state ``state`` ``(T,)``; orthographically those do not matter
    and the two signs span opposite depths.
    """
    n_frames, n_fingers = best.shape
    if candidates is None or candidates.joints is None:
        magnitude = abs_dz[:, layout.chains].reshape(n_frames, -1, 1, 1)
        return np.concatenate([magnitude, -magnitude], axis=2)
    full = (n_frames, 2, n_fingers, 2, 2, 2)
    frames, fingers = np.arange(n_frames)[:, None, None], np.arange(n_fingers)[None, :, None]
    own = np.array([0, 1])[None, None, :]
    first, second = (best[..., None] >> 2) & 1, (best[..., None] >> 1) & 1
    at = (frames, state[:, None, None], fingers)
    depths = np.stack([
        np.broadcast_to(candidates.bones[0][..., 2], full)[(*at, own, 0, 0)],
        np.broadcast_to(candidates.bones[1][..., 2], full)[(*at, first, own, 0)],
        np.broadcast_to(candidates.bones[2][..., 2], full)[(*at, first, second, own)],
    ], axis=2)                                                           # (T, F, 3, 2)
    return depths.reshape(n_frames, -1, 2, 1)


def _finger_odds(hyp: Hypotheses, settled: Settled, candidates: CandidateBlock | None,
                 abs_dz: np.ndarray, parts: PalmParts, bone_lengths: np.ndarray) -> np.ndarray:
    """Posterior log-odds of every finger bone's sign under the chosen tilt, ``(T, F, 3)``.

    ``candidates`` gives a pinhole clip's candidates block by block (``None``
    orthographically).
    """
    layout = parts.layout
    bone_log_odds, best = chosen_votes(hyp.case, settled)
    if candidates is None:
        chain_dz = _chain_depths(None, settled.state, best, abs_dz, layout)
    else:
        chain_dz = np.concatenate([
            _chain_depths(candidates(start, stop), settled.state[start:stop], best[start:stop],
                          abs_dz[start:stop], layout)
            for start, stop in _blocks(len(best))])
    return finger_signs(bone_log_odds, chain_dz,
                        TEMPORAL_FLOOR * bone_lengths[layout.chains].ravel())


def _discounted(confidence: np.ndarray, p_mirror: float) -> np.ndarray:
    """A sign's confidence when the whole clip is mirrored with probability ``p_mirror``.

    Kept within [0.5, 1]; NaN stays NaN.
    """
    mixed = confidence * (1.0 - p_mirror) + (1.0 - confidence) * p_mirror
    return np.clip(mixed, MIN_CONFIDENCE, MAX_CONFIDENCE)


def _confidence(solution: Solution, parts: PalmParts, n_joints: int) -> np.ndarray:
    """Each bone's sign confidence, discounted by the mirror, ``(T, J)``; NaN at the root."""
    settled = solution.settled
    p_mirror = float(sigmoid(-solution.mirror_log_odds))
    confidence = np.full((len(settled.state), n_joints), np.nan)
    confidence[:, parts.bones] = _discounted(sigmoid(np.abs(settled.tilt_log_odds)),
                                             p_mirror)[:, None]
    if parts.thumb_base >= 0:
        confidence[:, parts.thumb_base] = _discounted(
            sigmoid(np.abs(settled.thumb_log_odds)), p_mirror)
    confidence[:, parts.layout.chains] = _discounted(sigmoid(np.abs(solution.finger_odds)),
                                                     p_mirror)
    return confidence


def _chosen_palm(hyp: Hypotheses, settled: Settled, parts: PalmParts) -> np.ndarray:
    """The palm in each state with the thumb base on its settled sign, ``(T, 2, J, 3)``."""
    if hyp.thumb is None:
        return hyp.palm
    return _with_thumb(hyp.palm, hyp.thumb, settled.thumb_sign, parts.thumb_base)


def _orthographic_depths(solution: Solution, abs_dz: np.ndarray, skeleton: Skeleton,
                         parts: PalmParts) -> np.ndarray:
    """Depth of every joint relative to the root, ``(T, J)``, clip units."""
    settled = solution.settled
    frames = np.arange(len(settled.state))
    palm = _chosen_palm(solution.hypotheses, settled, parts)[frames, settled.state, :, 2]
    dz = np.zeros(abs_dz.shape)
    placed = parts.bones if parts.thumb_base < 0 else np.append(parts.bones, parts.thumb_base)
    dz[:, placed] = palm[:, placed] - palm[:, skeleton.parents[placed]]
    chains = parts.layout.chains
    dz[:, chains] = np.where(solution.finger_odds < 0, -1.0, 1.0) * abs_dz[:, chains]
    return accumulate_depths(dz, skeleton)


def _pinhole_points(solution: Solution, candidates: CandidateBlock,
                    layout: HandLayout) -> np.ndarray:
    """Joint positions of a pinhole solution, picked from its candidates, ``(T, J, 3)``.

    ``candidates`` gives them block by block (:data:`CANDIDATE_BLOCK_FRAMES`).
    """
    state, odds = solution.settled.state, solution.finger_odds
    return np.concatenate([_picked_points(state[start:stop], odds[start:stop],
                                          candidates(start, stop), layout)
                           for start, stop in _blocks(len(state))])


def _picked_points(state: np.ndarray, finger_odds: np.ndarray, candidates: FingerCandidates,
                   layout: HandLayout) -> np.ndarray:
    """Joint positions ``(T, J, 3)`` picked from ``candidates`` of the same ``T`` frames.

    ``state`` ``(T,)`` is each frame's palm state, ``finger_odds`` ``(T, F, 3)`` each
    finger bone's log-odds of the positive sign.
    """
    if candidates.palm is None or candidates.joints is None:
        raise ValueError("positions can only be picked from perspective candidates")
    frames = np.arange(len(state))
    xyz = candidates.palm[frames, state].copy()
    pick = (finger_odds < 0).astype(np.int64)                            # (T, F, 3)
    frame, finger = frames[:, None], np.arange(len(layout.fingers))[None, :]
    first, second, third = candidates.joints
    own = state[:, None]
    xyz[:, layout.chains[:, 0]] = first[frame, own, finger, pick[..., 0]]
    xyz[:, layout.chains[:, 1]] = second[frame, own, finger, pick[..., 0], pick[..., 1]]
    xyz[:, layout.chains[:, 2]] = third[frame, own, finger, pick[..., 0], pick[..., 1],
                                        pick[..., 2]]
    return xyz


def _lift_orthographic(image: np.ndarray, projected: np.ndarray, scale: np.ndarray,
                       skeleton: Skeleton, bone_lengths: np.ndarray, parts: PalmParts,
                       hand: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, Solution]:
    """Lift an orthographic clip: positions, length excess, scale and the solution."""
    abs_dz, _ = depth_magnitudes(projected, bone_lengths, scale)
    states = template_states(image, scale, abs_dz, skeleton, parts, bone_lengths)
    if states is not None:
        scale = states.scale
        abs_dz, _ = depth_magnitudes(projected, bone_lengths, scale)
    xy = image / scale[:, None, None]
    if states is None:
        planes = [parts.rigid] + ([parts.layout] if parts.thumb_base >= 0 else [])
        size = palm_size(skeleton, bone_lengths)
        hypotheses = [h for plane in planes for h in _orthographic_hypotheses(
            plane_states(xy, abs_dz, skeleton, parts, plane, scale, hand, size), xy, abs_dz,
            skeleton, parts, bone_lengths, hand)]
    else:
        hypotheses = _orthographic_hypotheses(states, xy, abs_dz, skeleton, parts,
                                              bone_lengths, hand)
    hyp, settled, odds = _choose(hypotheses, parts, bone_lengths)
    solution = Solution(hyp, settled, _finger_odds(hyp, settled, None, abs_dz, parts,
                                                   bone_lengths), odds)
    z = _orthographic_depths(solution, abs_dz, skeleton, parts)
    _, inconsistency = depth_magnitudes(projected, bone_lengths, scale)
    return orthographic_points(image, scale, z), inconsistency, scale, solution


def _lift_pinhole(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                  camera: Camera, parts: PalmParts, hand: str,
                  weak_scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, Solution]:
    """Lift a pinhole clip: the root's depth from the bone lengths, then signs on the rays.

    The root's depth comes from :func:`handdb.lifting.pinhole.estimate_root_depth`; the
    palm's states from plane fits walked along the rays
    (:func:`~handdb.lifting.palm_states.ray_plane_states`), and the fingers' candidates
    are the two roots of every bone's ray quadratic
    (:func:`handdb.lifting.finger_geometry.perspective_candidates`), so the hand prior
    judges the poses the camera can actually have produced.

    Returns
    -------
    xyz, inconsistency, solution
        ``(T, J, 3)`` positions and ``(T, J)`` length excess, clip units; the signs.
    """
    rays = camera_rays(uv, camera)
    root = skeleton.root
    parent, child = skeleton.bones.T
    depth = estimate_root_depth(uv, skeleton, bone_lengths, camera, weak_scale)
    metric_xy = (rays[..., :2] - rays[:, root : root + 1, :2]) * depth[:, None, None]
    abs_dz, _ = depth_magnitudes(projected_lengths(metric_xy, skeleton), bone_lengths,
                                 np.ones(len(uv)))
    planes = [parts.rigid] + ([parts.layout] if parts.thumb_base >= 0 else [])
    size = palm_size(skeleton, bone_lengths)
    hypotheses = [_pinhole_hypotheses(ray_plane_states(rays, depth, metric_xy, abs_dz,
                                                       skeleton, parts, plane, bone_lengths,
                                                       hand, size),
                                      rays, skeleton, parts, bone_lengths, hand)
                  for plane in planes]
    hyp, settled, odds = _choose(hypotheses, parts, bone_lengths)
    palm = _chosen_palm(hyp, settled, parts)

    def candidates(start: int, stop: int) -> FingerCandidates:
        return perspective_candidates(rays[start:stop], palm[start:stop], bone_lengths,
                                      parts.layout)

    solution = Solution(hyp, settled, _finger_odds(hyp, settled, candidates, abs_dz, parts,
                                                   bone_lengths), odds)
    xyz = _pinhole_points(solution, candidates, parts.layout)
    inconsistency = np.zeros(abs_dz.shape)
    inconsistency[:, child] = np.clip(
        np.linalg.norm(xyz[:, child] - xyz[:, parent], axis=-1) - bone_lengths[child], 0.0,
        None)
    return xyz, inconsistency, solution


def lift_kinematic(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                   camera: Camera, *, hand: str) -> LiftResult:
    """Lift with the rigid palm and the hand prior; see the module docstring.

    Parameters are those of :func:`handdb.lifting.lift`.
    """
    parts = palm_parts(skeleton)
    uv = denoise(uv, ~finite_points(uv))[0]
    image = centred_pixels(uv, camera)
    projected = projected_lengths(image, skeleton)
    scale = smooth_scale(eq6_scale(projected, bone_lengths, rank=SCALE_RANK))
    if camera.model == "pinhole":
        xyz, inconsistency, solution = _lift_pinhole(uv, skeleton, bone_lengths, camera,
                                                     parts, hand, scale)
        scale = np.full(scale.shape, np.nan)
    else:
        xyz, inconsistency, scale, solution = _lift_orthographic(
            image, projected, scale, skeleton, bone_lengths, parts, hand)
    inconsistency[:, skeleton.root] = 0.0
    odds = solution.mirror_log_odds
    ambiguous = odds < np.log(MIRROR_SETTLED_ODDS)
    note = (f"clip-wide mirror not settled: the chosen depth signs are only "
            f"{np.exp(odds):.3g} times as likely as all of them flipped" if ambiguous else "")
    return LiftResult(xyz=xyz, sign_confidence=_confidence(solution, parts, skeleton.n_joints),
                      length_inconsistency=inconsistency, scale=scale, method="kinematic",
                      mirror_ambiguous=bool(ambiguous), mirror_log_odds=float(odds),
                      note=note)
