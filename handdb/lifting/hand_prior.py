"""The hand prior: how plausible each finger's depth-sign state is, given the palm.

For each palm state (the palm's two mirror tilts) the palm's normal points to the palmar
side as the hand's handedness says (``(index MCP − wrist) × (little MCP − wrist)`` for a
right hand, the opposite for a left one), and each finger's three bones below the palm
take one of eight sign states. A state is scored by its flexion angles in the finger's
plane (the plane of the finger's metacarpal and the palm normal): each joint within its
range of motion, flexing toward the palm, the DIP about 2/3 of the PIP, no joint far
behind the palm. Scores are log-likelihoods.

The scoring runs in two compiled kernels (:mod:`handdb.compiled`) over frames,
palm states, fingers and sign states, with no temporary arrays: the first puts every
candidate bone in its finger's frame, numpy takes the arctangents (vectorised, several
times faster than one at a time), the second scores the states and sums them up.

Orthographically (:func:`score_mirrored_fingers`) the first kernel builds the candidate
bones ``(dx, dy, ±|dZ|)`` from the image itself, the six distinct ones of the 14 (a bone's
vector depends on its own sign only), and works out palm state 0 only: state 1 is its
mirror image (``z → −z``), and a mirror, being improper, turns the palm's normal
``n`` into ``−M n`` (``M = diag(1, 1, −1)``) and its forward axis ``f`` into ``M f``. A
candidate bone ``v`` of state 1 therefore rises ``v·(−M n) = −(M v)·n`` toward the palmar
side and runs ``v·M f = (M v)·f`` ahead, where ``M v`` is the candidate with every sign
flipped: state 1's components, base heights and angles are state 0's of the
complementary candidate, negated where they cross the palm plane. Negation is exact in
floating point, so the derived half equals what computing it would give, bit for bit.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from handdb.compiled import kernel
from handdb.hand.anatomy import DIP_PIP_COUPLING, RANGE_OF_MOTION_DEG
from handdb.hand.layout import CHAIN_BONES, HandLayout
from handdb.lifting.finger_geometry import FingerCandidates, anchor_joints
from handdb.lifting.temporal import NEGLIGIBLE_NATS

#: Every sign pattern of a finger's three bones, ``(8, 3)``; row ``k`` has bit ``b`` of
#: ``k`` (most significant first) set where bone ``b`` is negative.
SIGN_STATES = np.array(list(itertools.product((1.0, -1.0), repeat=CHAIN_BONES)))

#: Candidate bones of a finger: two first bones, four second, eight third.
CANDIDATE_BONES = 14

#: Distinct candidate bones of a finger orthographically: each bone under either sign.
OWN_SIGN_BONES = 2 * CHAIN_BONES

#: Where each of the 14 candidates (in :func:`_candidate`'s order) is among the six
#: distinct ones orthographically, bone ``i`` with its own sign ``s`` at ``2 i + s``.
OWN_SIGN_SLOTS = np.array([2 * bone + signs[-1]
                           for bone in range(CHAIN_BONES)
                           for signs in itertools.product((0, 1), repeat=bone + 1)])

#: How far beyond a joint's active range (:data:`handdb.hand.anatomy.RANGE_OF_MOTION_DEG`)
#: the prior admits a bone's angle without cost, degrees: it measures the angle in the
#: finger's plane from noisy image points, not about the joint's own axes.
PRIOR_MARGIN_DEG = 15.0

#: The joint axes whose ranges bound each bone of a chain below the palm, base to tip: a
#: long finger's MCP, PIP and DIP flexion; the thumb's metacarpal lifts off the palm by
#: palmar abduction at the CMC, then its MCP and IP flex.
LONG_FINGER_AXES = (("index", "mcp", "flexion"), ("index", "pip", "flexion"),
                    ("index", "dip", "flexion"))
THUMB_AXES = (("thumb", "cmc", "abduction"), ("thumb", "mcp", "flexion"),
              ("thumb", "ip", "flexion"))


def _ranges_deg(axes: tuple[tuple[str, str, str], ...]) -> np.ndarray:
    """``(3, 2)`` ranges of a chain's bones with the prior's margin, degrees."""
    return np.array([RANGE_OF_MOTION_DEG[axis] for axis in axes]) + (-PRIOR_MARGIN_DEG,
                                                                       PRIOR_MARGIN_DEG)


#: Angle ranges of a long finger's three bones and of the thumb's, degrees (flexion
#: positive).
LONG_FINGER_RANGE_DEG = _ranges_deg(LONG_FINGER_AXES)
THUMB_RANGE_DEG = _ranges_deg(THUMB_AXES)

#: Softness of a range limit: a violation by this much costs one unit of log-likelihood.
RANGE_SOFTNESS_DEG = 10.0

#: Standard deviation of the DIP flexion about :data:`~handdb.hand.anatomy.DIP_PIP_COUPLING`
#: times the PIP's, degrees.
COUPLING_SIGMA_DEG = 25.0

#: How far a finger's joints may go to the back of the palm plane, as a share of the
#: finger's first bone below the palm: about sin 30° for a hyperextended MCP; the thumb
#: stays in front of the palm.
FINGER_DORSAL_MARGIN = 0.5
THUMB_DORSAL_MARGIN = 0.0

#: Softness of that limit, as a share of the first bone.
DORSAL_SOFTNESS = 0.1

#: A weak prior toward relaxed poses: each joint's flexion ~ N(centre, sigma), degrees.
#: It settles the frames where a finger fits either palm tilt, flexed a little or a lot.
COMFORT_CENTRE_DEG = 15.0
COMFORT_SIGMA_DEG = 45.0

HANDEDNESS = {"right": 1.0, "left": -1.0}



@dataclass(frozen=True)
class FingerScores:
    """How well each finger's sign states fit the hand prior, per frame and palm state.

    Attributes
    ----------
    anatomy
        ``(T, 2, F, 8) float64``: log-likelihood of each state from the ranges of motion,
        the dorsal limit and the DIP-PIP coupling; 0 where a finger's bones have no image
        points. The clip-wide mirror is judged on it alone.
    evidence
        ``(T, 2, F) float64``: log of the summed likelihood of the eight states, with the
        weak prior toward relaxed poses (which breaks ties but says nothing about the
        mirror) added to ``anatomy``.
    bone_log_odds
        ``(T, 2, F, 3) float64``: each bone's log-odds of the positive sign, marginalised
        over the finger's states.
    best
        ``(T, 2, F) int64``: the most likely state.
    """

    anatomy: np.ndarray
    evidence: np.ndarray
    bone_log_odds: np.ndarray
    best: np.ndarray


def score_fingers(candidates: FingerCandidates, bone_lengths: np.ndarray,
                  layout: HandLayout, hand: str) -> FingerScores:
    """Score each finger's sign states under each palm state with the hand prior.

    Parameters
    ----------
    candidates
        Palm anchors and candidate bones (:mod:`handdb.lifting.finger_geometry`).
    bone_lengths
        ``(J,) float64``, clip units.
    layout, hand
        The skeleton's palm and fingers, and which hand the clip shows.

    Returns
    -------
    FingerScores
    """
    anchors = candidates.anchors
    n_frames, n_fingers = len(anchors), len(layout.fingers)
    full = (n_frames, 2, n_fingers, 2, 2, 2, 3)
    first = np.broadcast_to(candidates.bones[0], full)[:, :, :, :, 0, 0]
    second = np.broadcast_to(candidates.bones[1], full)[:, :, :, :, :, 0]
    third = np.broadcast_to(candidates.bones[2], full)
    palmar = np.empty((n_frames, 2, n_fingers, CANDIDATE_BONES))
    ahead = np.empty(palmar.shape)
    base_height = np.empty((n_frames, 2, n_fingers))
    _palm_frame_components(anchors, first, second, third, HANDEDNESS[hand], palmar, ahead,
                           base_height)
    return _score(np.arctan2(palmar, ahead), palmar, base_height, np.arange(CANDIDATE_BONES),
                  bone_lengths, layout)


def score_mirrored_fingers(xy: np.ndarray, abs_dz: np.ndarray, palm_z: np.ndarray,
                           bone_lengths: np.ndarray, layout: HandLayout,
                           hand: str) -> FingerScores:
    """Score the sign states orthographically, palm state 1 being state 0's mirror image.

    Gives what :func:`score_fingers` gives for the candidates whose anchors have the palm
    depths ``palm_z`` in state 0 and ``−palm_z`` in state 1 and whose bones are
    ``(dx, dy, ±|dZ|)``, bit for bit, working out the geometry of state 0's six distinct
    candidate bones only (see the module docstring).

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.
    palm_z
        ``(T, J) float64``, clip units: depth of the palm joints relative to the root in
        palm state 0 (other joints: ignored).
    bone_lengths
        ``(J,) float64``, clip units.
    layout, hand
        The skeleton's palm and fingers, and which hand the clip shows.

    Returns
    -------
    FingerScores
    """
    n_frames, n_fingers = len(xy), len(layout.fingers)
    parents = np.column_stack([layout.chain_bases, layout.chains[:, :-1]])
    palmar = np.empty((n_frames, 2, n_fingers, OWN_SIGN_BONES))
    ahead = np.empty((n_frames, n_fingers, OWN_SIGN_BONES))
    base_height = np.empty((n_frames, 2, n_fingers))
    _mirrored_components(xy, abs_dz, palm_z, anchor_joints(layout), layout.chains, parents,
                         HANDEDNESS[hand], palmar, ahead, base_height)
    angle = np.empty(palmar.shape)
    np.arctan2(palmar[:, 0], ahead, out=angle[:, 0])
    _mirror_angles(angle)
    return _score(angle, palmar, base_height, OWN_SIGN_SLOTS, bone_lengths, layout)


def _score(angle: np.ndarray, palmar: np.ndarray, base_height: np.ndarray,
           slots: np.ndarray, bone_lengths: np.ndarray, layout: HandLayout) -> FingerScores:
    """Score the states from the candidates in their fingers' frames.

    ``angle`` ``(T, 2, F, K)``, radians, is each candidate bone's direction in its
    finger's plane; ``palmar`` ``(T, 2, F, K)`` and ``base_height`` ``(T, 2, F)``, clip
    units, its rise toward the palmar side and the finger base's height over the palm.
    ``slots`` ``(14,)`` says where along ``K`` each candidate (:func:`_candidate`'s order)
    is.
    """
    thumb = layout.is_thumb
    ranges = np.radians(np.where(thumb[:, None, None], THUMB_RANGE_DEG,
                                 LONG_FINGER_RANGE_DEG))                 # (F, 3, 2)
    first_bone = bone_lengths[layout.chains[:, 0]]
    margin = np.where(thumb, THUMB_DORSAL_MARGIN, FINGER_DORSAL_MARGIN) * first_bone
    scores = FingerScores(anatomy=np.empty(base_height.shape + (len(SIGN_STATES),)),
                          evidence=np.empty(base_height.shape),
                          bone_log_odds=np.empty(base_height.shape + (CHAIN_BONES,)),
                          best=np.empty(base_height.shape, dtype=np.int64))
    _score_states(angle, palmar, base_height, slots, ranges, np.radians(RANGE_SOFTNESS_DEG),
                  ~thumb, margin, DORSAL_SOFTNESS * first_bone, scores.anatomy,
                  scores.evidence, scores.bone_log_odds, scores.best)
    return scores


@kernel
def _wrap(angle: float) -> float:
    """An angle in (-2 pi, 2 pi) brought to [-pi, pi)."""
    if angle >= math.pi:
        return angle - 2.0 * math.pi
    if angle < -math.pi:
        return angle + 2.0 * math.pi
    return angle


@kernel
def _outside(angle: float, low: float, high: float, softness: float) -> float:
    return ((max(low - angle, 0.0) + max(angle - high, 0.0)) / softness) ** 2


@kernel
def _dorsal(height: float, margin: float, softness: float) -> float:
    return (max(-height - margin, 0.0) / softness) ** 2


@kernel
def _dot(u: np.ndarray, v: np.ndarray) -> float:
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@kernel
def _palm_frame_components(anchors, first, second, third, handedness, palmar, ahead,
                           base_height):
    """Each candidate bone in its finger's frame: toward the palmar side and ahead.

    ``anchors`` is ``(T, 2, 3 + F, 3)``; ``first``, ``second``, ``third`` are the candidate
    bones ``(T, 2, F, 2, 3)``, ``(T, 2, F, 2, 2, 3)``, ``(T, 2, F, 2, 2, 2, 3)``. Fills
    ``palmar`` and ``ahead`` ``(2, F, 14, T)`` (the candidates in :func:`_candidate`'s
    order) and ``base_height`` ``(T, 2, F)``, the height of each finger's base over the
    palm plane.
    """
    n_frames, n_fingers = anchors.shape[0], first.shape[2]
    across, along, normal = np.empty(3), np.empty(3), np.empty(3)
    forward = np.empty(3)
    for t in range(n_frames):
        for p in range(2):
            for k in range(3):
                across[k] = anchors[t, p, 1, k] - anchors[t, p, 0, k]
                along[k] = anchors[t, p, 2, k] - anchors[t, p, 0, k]
            normal[0] = across[1] * along[2] - across[2] * along[1]
            normal[1] = across[2] * along[0] - across[0] * along[2]
            normal[2] = across[0] * along[1] - across[1] * along[0]
            norm = math.sqrt(_dot(normal, normal))
            for k in range(3):
                normal[k] *= handedness / norm
            for f in range(n_fingers):
                for k in range(3):
                    forward[k] = anchors[t, p, 3 + f, k] - anchors[t, p, 0, k]
                height = _dot(forward, normal)
                base_height[t, p, f] = height
                for k in range(3):
                    forward[k] -= height * normal[k]
                norm = math.sqrt(_dot(forward, forward))
                for k in range(3):
                    forward[k] /= norm
                for a in range(2):
                    _project(first[t, p, f, a], normal, forward, palmar[t, p, f],
                             ahead[t, p, f], _candidate(a))
                    for b in range(2):
                        _project(second[t, p, f, a, b], normal, forward, palmar[t, p, f],
                                 ahead[t, p, f], _candidate(a, b))
                        for c in range(2):
                            _project(third[t, p, f, a, b, c], normal, forward,
                                     palmar[t, p, f], ahead[t, p, f], _candidate(a, b, c))


@kernel
def _mirrored_components(xy, abs_dz, palm_z, anchors, chains, parents, handedness, palmar,
                         ahead, base_height):
    """Like :func:`_palm_frame_components` for orthographic candidates, from the image.

    ``xy`` is ``(T, J, 2)``, ``abs_dz`` and ``palm_z`` ``(T, J)`` (state 0's palm depths);
    ``anchors`` ``(3 + F,)`` the joints of
    :attr:`handdb.lifting.finger_geometry.FingerCandidates.anchors`, ``chains`` and
    ``parents`` ``(F, 3)`` each finger's bones below the palm. Fills ``palmar`` ``(T, 2, F,
    6)`` and ``base_height`` ``(T, 2, F)`` for both palm states, state 1 mirrored from
    state 0, and ``ahead`` ``(T, F, 6)`` for state 0; bone ``i`` with sign ``s`` is at
    ``2 i + s`` (:data:`OWN_SIGN_SLOTS`).
    """
    n_frames, n_fingers = xy.shape[0], chains.shape[0]
    corner = np.empty((3, 3))
    across, along, normal = np.empty(3), np.empty(3), np.empty(3)
    forward, bone = np.empty(3), np.empty(3)
    for t in range(n_frames):
        for i in range(3):
            corner[i, 0], corner[i, 1] = xy[t, anchors[i], 0], xy[t, anchors[i], 1]
            corner[i, 2] = palm_z[t, anchors[i]]
        for k in range(3):
            across[k] = corner[1, k] - corner[0, k]
            along[k] = corner[2, k] - corner[0, k]
        normal[0] = across[1] * along[2] - across[2] * along[1]
        normal[1] = across[2] * along[0] - across[0] * along[2]
        normal[2] = across[0] * along[1] - across[1] * along[0]
        norm = math.sqrt(_dot(normal, normal))
        for k in range(3):
            normal[k] *= handedness / norm
        for f in range(n_fingers):
            base = anchors[3 + f]
            forward[0] = xy[t, base, 0] - corner[0, 0]
            forward[1] = xy[t, base, 1] - corner[0, 1]
            forward[2] = palm_z[t, base] - corner[0, 2]
            height = _dot(forward, normal)
            base_height[t, 0, f], base_height[t, 1, f] = height, -height
            for k in range(3):
                forward[k] -= height * normal[k]
            norm = math.sqrt(_dot(forward, forward))
            for k in range(3):
                forward[k] /= norm
            for i in range(CHAIN_BONES):
                child, parent = chains[f, i], parents[f, i]
                bone[0] = xy[t, child, 0] - xy[t, parent, 0]
                bone[1] = xy[t, child, 1] - xy[t, parent, 1]
                for sign in range(2):
                    bone[2] = abs_dz[t, child] if sign == 0 else -abs_dz[t, child]
                    palmar[t, 0, f, 2 * i + sign] = _dot(bone, normal)
                    ahead[t, f, 2 * i + sign] = _dot(bone, forward)
                    palmar[t, 1, f, 2 * i + 1 - sign] = -palmar[t, 0, f, 2 * i + sign]


@kernel
def _mirror_angles(angle):
    """Fill palm state 1 of ``angle`` ``(T, 2, F, 6)`` from state 0.

    Bone ``i`` with sign ``s`` is at ``2 i + s``; in state 1 its angle is minus that of
    the same bone with the other sign in state 0.
    """
    n_frames, _, n_fingers, n_candidates = angle.shape
    for t in range(n_frames):
        for f in range(n_fingers):
            for index in range(n_candidates):
                angle[t, 1, f, index ^ 1] = -angle[t, 0, f, index]


@kernel
def _project(bone, normal, forward, palmar, ahead, index):
    """Write ``bone``'s components along ``normal`` and ``forward`` at ``index``."""
    palmar[index] = bone[0] * normal[0] + bone[1] * normal[1] + bone[2] * normal[2]
    ahead[index] = bone[0] * forward[0] + bone[1] * forward[1] + bone[2] * forward[2]


@kernel
def _candidate(a: int, b: int = -1, c: int = -1) -> int:
    """Position of a candidate bone among a finger's 14, by the signs above and at it."""
    if b < 0:
        return a
    if c < 0:
        return 2 + 2 * a + b
    return 6 + 4 * a + 2 * b + c


@kernel
def _score_states(angle, palmar, base_height, slots, ranges, range_softness, coupled,
                  margin, dorsal_softness, anatomy, evidence, bone_log_odds, best):
    """Fill the arrays of a :class:`FingerScores` (see there for their shapes).

    ``angle`` and ``palmar`` are ``(T, 2, F, K)``: each candidate bone's direction in its
    finger's plane and its rise toward the palmar side, candidate ``k`` (in
    :func:`_candidate`'s order) at ``slots[k]``; ``base_height`` ``(T, 2, F)``.
    """
    ratio_sigma = math.radians(COUPLING_SIGMA_DEG)
    centre, spread = math.radians(COMFORT_CENTRE_DEG), math.radians(COMFORT_SIGMA_DEG)
    n_frames, n_fingers = angle.shape[0], angle.shape[2]
    low, high = ranges[..., 0], ranges[..., 1]
    log_likelihood = np.empty(8)
    for t in range(n_frames):
        for p in range(2):
            for f in range(n_fingers):
                for a in range(2):
                    mcp = angle[t, p, f, slots[_candidate(a)]]
                    knuckle = base_height[t, p, f] + palmar[t, p, f, slots[_candidate(a)]]
                    cost_a = (_outside(mcp, low[f, 0], high[f, 0], range_softness)
                              + _dorsal(knuckle, margin[f], dorsal_softness[f]))
                    relaxed_a = ((mcp - centre) / spread) ** 2
                    for b in range(2):
                        second = slots[_candidate(a, b)]
                        pip = _wrap(angle[t, p, f, second] - mcp)
                        middle = knuckle + palmar[t, p, f, second]
                        cost_ab = (cost_a
                                   + _outside(pip, low[f, 1], high[f, 1], range_softness)
                                   + _dorsal(middle, margin[f], dorsal_softness[f]))
                        relaxed_ab = relaxed_a + ((pip - centre) / spread) ** 2
                        for c in range(2):
                            third = slots[_candidate(a, b, c)]
                            dip = _wrap(angle[t, p, f, third] - angle[t, p, f, second])
                            end = middle + palmar[t, p, f, third]
                            cost = (cost_ab
                                    + _outside(dip, low[f, 2], high[f, 2], range_softness)
                                    + _dorsal(end, margin[f], dorsal_softness[f]))
                            if coupled[f]:
                                cost += ((dip - DIP_PIP_COUPLING * pip) / ratio_sigma) ** 2
                            relaxed = relaxed_ab + ((dip - centre) / spread) ** 2
                            state = 4 * a + 2 * b + c
                            anatomy[t, p, f, state] = 0.0 if math.isnan(cost) else -0.5 * cost
                            log_likelihood[state] = anatomy[t, p, f, state] + (
                                0.0 if math.isnan(relaxed) else -0.5 * relaxed)
                _summarise(log_likelihood, evidence, bone_log_odds, best, t, p, f)


@kernel
def _summarise(log_likelihood, evidence, bone_log_odds, best, t, p, f):
    """Log evidence, per-bone log-odds and the best of a finger's eight states."""
    top = _argmax(log_likelihood)
    best[t, p, f] = top
    peak = log_likelihood[top]
    total = first = second = third = 0.0
    for state in range(8):
        gap = log_likelihood[state] - peak
        if gap == 0.0:
            weight = 1.0
        else:
            weight = math.exp(gap) if gap > -NEGLIGIBLE_NATS else 0.0
        total += weight
        first += weight if state < 4 else 0.0
        second += weight if state % 4 < 2 else 0.0
        third += weight if state % 2 == 0 else 0.0
    evidence[t, p, f] = peak + math.log(total)
    for bone, positive in enumerate((first, second, third)):
        bone_log_odds[t, p, f, bone] = math.log(positive / (total - positive))


@kernel
def _argmax(values):
    """``np.argmax`` of a short 1D array, NaN counting as the largest, inline.

    numba's ``np.argmax`` costs about as much as the eight exponentials of
    :func:`_summarise`.
    """
    top = 0
    for index in range(len(values)):
        if math.isnan(values[index]):
            return index
        if values[index] > values[top]:
            top = index
    return top
