"""The default lifting method, ``kinematic``: depth signs settled with what hands can do.

Per frame, the unsigned depth of every bone follows from eq. 5 at a robust, smoothed scale:
the second-largest ratio of image to bone length (one outlier bone allowed), then an upper
percentile over a window of frames (:func:`handdb.lifting.temporal.smooth_scale`). The
signs are then chosen in three steps:

1. **Palm.** The palm (wrist, carpometacarpal and long-finger MCP joints) is near rigid and
   near planar: of the sign patterns of its bones, the one whose joints fit a plane best is
   kept, with its mirror image (the palm tilted the other way) as the only alternative
   (:mod:`handdb.lifting.palm`).
2. **Fingers.** Under each palm state, each finger's three bones below the palm take one
   of eight sign states, scored by the hand prior (:mod:`handdb.lifting.hand_prior`):
   ranges of motion, flexion toward the palm, the DIP about 2/3 of the PIP.
3. **Time.** Signed depths move smoothly: the palm's tilt and every bone's sign are chains
   over the frames under a constant-velocity prior (:mod:`handdb.lifting.temporal`), so a
   sign changes only where its bone passes through the image plane, and there the motion
   goes on rather than bouncing back. The palm's evidence is the fingers' likelihood under
   each tilt, each finger's say in a frame capped (``FINGER_VOTE_CAP``) so that one finger
   the prior fits badly cannot flip the palm.

The confidence of each bone's sign is its posterior, discounted by the probability that
the whole clip is mirrored: flipping every sign at once changes only the
flexion-direction evidence, so a clip without clear flexion (a flat hand) cannot settle it,
and the result says so (``mirror_ambiguous``).

With a pinhole camera the root's depth comes from the bone lengths and the rays
(:func:`handdb.lifting.pinhole.estimate_root_depth`), then every joint is placed on its ray
and the hand prior chooses among the two solutions of every bone.

Its accuracy, on real captures and synthetic hands, is in ``benchmarks/RESULTS-lifting.md``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from handdb.clip import Camera
from handdb.compiled import kernel
from handdb.hand.layout import CHAIN_BONES, HandLayout, hand_layout
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
from handdb.lifting.hand_prior import score_fingers, score_mirrored_fingers
from handdb.lifting.palm import palm_signs
from handdb.lifting.pinhole import camera_rays, estimate_root_depth, walk_rays
from handdb.lifting.result import LiftResult
from handdb.lifting.temporal import acceleration_spread, sigmoid, sign_posterior, smooth_scale

#: The scale of a frame lets its most stretched bone be an outlier (see
#: :func:`handdb.lifting.geometry.eq6_scale`): trackers' bones vary in length.
SCALE_RANK = 2

#: Smallest spread of a bone's frame-to-frame depth change, as a share of its length.
TEMPORAL_FLOOR = 0.02

#: The clip-wide mirror counts as settled when it is this many times less likely.
MIRROR_SETTLED_ODDS = 20.0

#: Bounds of a sign's confidence: a probability that the chosen sign is right.
MIN_CONFIDENCE, MAX_CONFIDENCE = 0.5, 1.0

#: Largest say one finger has on a frame's palm tilt, nats: a finger the prior models badly
#: (an opposed thumb) or a mis-tracked one cannot outvote the others (on the real DHG
#: capture the thumb alone, confidently wrong, flipped the palm for half the clip).
FINGER_VOTE_CAP = 4.0


@dataclass(frozen=True)
class SignSolution:
    """The depth signs :func:`resolve_signs` settled on.

    Attributes
    ----------
    signs
        ``(T, J) float64`` of ±1 (``+``: the child is farther from the camera); NaN at the
        root.
    confidence
        ``(T, J) float64`` in [0.5, 1]; NaN at the root.
    mirror_log_odds
        Log-odds of the chosen signs against their clip-wide mirror (>= 0).
    palm_state
        ``(T,) int64``: the palm state (0 or 1) of ``candidates`` chosen in each frame.
    finger_signs
        ``(T, F, 3) float64`` of ±1: the signs of each finger's bones below the palm.
    candidates
        The candidates the signs were chosen from (pinhole only; ``None``
        orthographically, where they follow from the image and the depths).
    """

    signs: np.ndarray
    confidence: np.ndarray
    mirror_log_odds: float
    palm_state: np.ndarray
    finger_signs: np.ndarray
    candidates: FingerCandidates | None


def resolve_signs(
    xy: np.ndarray,
    abs_dz: np.ndarray,
    bone_lengths: np.ndarray,
    skeleton: Skeleton,
    hand: str,
    candidates_for: Callable[[np.ndarray], FingerCandidates] | None = None,
) -> SignSolution:
    """Depth sign of every bone, its confidence and the odds against the mirror.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.
    bone_lengths
        ``(J,) float64``, clip units.
    skeleton, hand
        The clip's skeleton and hand.
    candidates_for
        Builds the finger candidates from the palm's sign pattern ``(T, P)`` (state 0;
        state 1 is its mirror). Default: orthographic candidates from ``xy`` and
        ``abs_dz``, scored by :func:`handdb.lifting.hand_prior.score_mirrored_fingers`.

    Returns
    -------
    SignSolution
    """
    layout = hand_layout(skeleton)
    n_frames = len(xy)
    palm = palm_signs(xy, abs_dz, skeleton, layout)                      # (T, P)
    palm_dz = np.zeros((n_frames, skeleton.n_joints))
    palm_dz[:, layout.palm_bones] = palm * abs_dz[:, layout.palm_bones]
    palm_z = accumulate_depths(palm_dz, skeleton)
    if candidates_for is None:
        candidates = None
        scores = score_mirrored_fingers(xy, abs_dz, palm_z, bone_lengths, layout, hand)
    else:
        candidates = candidates_for(palm)
        scores = score_fingers(candidates, bone_lengths, layout, hand)
    votes = np.clip(scores.evidence[:, 0] - scores.evidence[:, 1], -FINGER_VOTE_CAP,
                    FINGER_VOTE_CAP)                                      # (T, F)
    palm_depths = _palm_depths(candidates, palm_z, skeleton, layout)     # (T, 1, 2, P)
    floor = TEMPORAL_FLOOR * np.nanmean(bone_lengths[layout.palm_bones], keepdims=True)
    palm_odds = sign_posterior(votes.sum(axis=1, keepdims=True), palm_depths,
                               acceleration_spread(palm_depths[:, :, 0], floor))[:, 0]
    state = (palm_odds < 0).astype(np.int64)
    best = np.empty((n_frames, len(layout.fingers)), dtype=np.int64)
    chosen = np.empty(best.shape + (CHAIN_BONES,))
    mirror_gap = np.empty(best.shape)
    _pick_palm_state(scores.anatomy, scores.bone_log_odds, scores.best, state, chosen, best,
                     mirror_gap)

    chain_dz = _chain_depths(candidates, state, best, abs_dz, layout)
    floor = TEMPORAL_FLOOR * bone_lengths[layout.chains].ravel()
    finger_odds = sign_posterior(chosen.reshape(n_frames, -1), chain_dz,
                                 acceleration_spread(chain_dz[:, :, 0], floor)
                                 ).reshape(chosen.shape)
    finger_signs = np.where(finger_odds < 0, -1.0, 1.0)

    # The mirror flips the palm tilt and every finger state at once. Compare each frame's
    # best pose under the chosen tilt with its exact mirror image, on anatomy alone.
    mirror_log_odds = float(np.sum(mirror_gap))
    if mirror_log_odds < 0:
        mirror_log_odds, state, finger_signs = -mirror_log_odds, 1 - state, -finger_signs

    signs = np.full((n_frames, skeleton.n_joints), np.nan)
    confidence = np.full(signs.shape, np.nan)
    _fill_signs(palm, state, finger_signs, sigmoid(np.abs(palm_odds)),
                sigmoid(np.abs(finger_odds)), sigmoid(-mirror_log_odds), layout.palm_bones,
                layout.chains, signs, confidence)
    return SignSolution(signs=signs, confidence=confidence, mirror_log_odds=mirror_log_odds,
                        palm_state=state, finger_signs=finger_signs, candidates=candidates)


@kernel
def _pick_palm_state(anatomy, bone_log_odds, best_states, state, chosen, best, mirror_gap):
    """Each frame's finger scores under its palm state ``state`` ``(T,)``.

    Takes :class:`handdb.lifting.hand_prior.FingerScores`' ``anatomy``,
    ``bone_log_odds`` and ``best`` (``best_states``); fills ``chosen`` ``(T, F, 3)`` and
    ``best`` ``(T, F)`` with the latter two under the frame's palm state, and
    ``mirror_gap`` ``(T, F)`` with the anatomy of each finger's best state less that of
    its mirror image (every sign flipped, under the other palm state).
    """
    n_frames, _, n_fingers, n_states = anatomy.shape
    for t in range(n_frames):
        own = state[t]
        for f in range(n_fingers):
            top = best_states[t, own, f]
            best[t, f] = top
            for bone in range(chosen.shape[2]):
                chosen[t, f, bone] = bone_log_odds[t, own, f, bone]
            mirror_gap[t, f] = (anatomy[t, own, f, top]
                                - anatomy[t, 1 - own, f, n_states - 1 - top])


@kernel
def _fill_signs(palm, state, finger_signs, palm_confidence, finger_confidence, p_mirror,
                palm_bones, chains, signs, confidence):
    """Write every bone's sign and its confidence, discounted by the mirror, per frame.

    ``palm`` ``(T, P)`` is the palm's sign pattern in state 0 and ``state`` ``(T,)`` the
    chosen state; ``finger_signs`` ``(T, F, 3)``; the confidences ``(T,)`` and ``(T, F,
    3)`` are before the discount by ``p_mirror``, the probability that the whole clip is
    mirrored. Fills ``signs`` and ``confidence`` ``(T, J)`` at ``palm_bones`` ``(P,)`` and
    ``chains`` ``(F, 3)``.
    """
    n_frames, n_fingers, n_bones = finger_signs.shape
    for t in range(n_frames):
        tilt = 1.0 - 2.0 * state[t]
        palm_sure = _discounted(palm_confidence[t], p_mirror)
        for i in range(len(palm_bones)):
            signs[t, palm_bones[i]] = palm[t, i] * tilt
            confidence[t, palm_bones[i]] = palm_sure
        for f in range(n_fingers):
            for b in range(n_bones):
                signs[t, chains[f, b]] = finger_signs[t, f, b]
                confidence[t, chains[f, b]] = _discounted(finger_confidence[t, f, b],
                                                          p_mirror)


@kernel
def _discounted(confidence, p_mirror):
    """A sign's confidence when the whole clip is mirrored with probability ``p_mirror``.

    Kept within [0.5, 1]; NaN stays NaN.
    """
    mixed = confidence * (1.0 - p_mirror) + (1.0 - confidence) * p_mirror
    if math.isnan(mixed):
        return mixed
    return min(max(mixed, MIN_CONFIDENCE), MAX_CONFIDENCE)


def _palm_depths(candidates: FingerCandidates | None, palm_z: np.ndarray,
                 skeleton: Skeleton, layout: HandLayout) -> np.ndarray:
    """Depth of the palm's joints relative to the root in each palm state, ``(T, 1, 2, P)``.

    Orthographically state 1 is the mirror of state 0 (``palm_z``); through a pinhole the
    candidates' palms are used as they are.
    """
    if candidates is None or candidates.palm is None:
        z = palm_z[:, layout.palm_bones]
        return np.stack([z, -z], axis=1)[:, None]
    z = candidates.palm[..., 2]                                          # (T, 2, J)
    return (z[:, :, layout.palm_bones] - z[:, :, skeleton.root, None])[:, None]


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


def _chosen_points(solution: SignSolution, skeleton: Skeleton) -> np.ndarray:
    """Joint positions of a pinhole solution, picked from its candidates, ``(T, J, 3)``."""
    layout = hand_layout(skeleton)
    candidates = solution.candidates
    if candidates is None or candidates.palm is None or candidates.joints is None:
        raise ValueError("positions can only be picked from perspective candidates")
    frames = np.arange(len(solution.palm_state))
    xyz = candidates.palm[frames, solution.palm_state].copy()
    pick = (solution.finger_signs < 0).astype(np.int64)                  # (T, F, 3)
    frame, finger = frames[:, None], np.arange(len(layout.fingers))[None, :]
    first, second, third = candidates.joints
    state = solution.palm_state[:, None]
    xyz[:, layout.chains[:, 0]] = first[frame, state, finger, pick[..., 0]]
    xyz[:, layout.chains[:, 1]] = second[frame, state, finger, pick[..., 0], pick[..., 1]]
    xyz[:, layout.chains[:, 2]] = third[frame, state, finger, pick[..., 0], pick[..., 1],
                                        pick[..., 2]]
    return xyz


def _lift_pinhole(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                  camera: Camera, hand: str,
                  weak_scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, SignSolution]:
    """Lift a pinhole clip: the root's depth from the bone lengths, then signs on the rays.

    The root's depth comes from :func:`handdb.lifting.pinhole.estimate_root_depth`. The
    palm and finger candidates are then the two roots of every bone's ray quadratic
    (:func:`handdb.lifting.finger_geometry.perspective_candidates`), so the hand prior
    judges the poses the camera can actually have produced.

    Returns
    -------
    xyz, inconsistency, solution
        ``(T, J, 3)`` positions and ``(T, J)`` length excess, clip units; the signs.
    """
    layout = hand_layout(skeleton)
    rays = camera_rays(uv, camera)
    root = skeleton.root
    parent, child = skeleton.bones.T
    depth = estimate_root_depth(uv, skeleton, bone_lengths, camera, weak_scale)
    metric_xy = (rays[..., :2] - rays[:, root : root + 1, :2]) * depth[:, None, None]
    abs_dz, _ = depth_magnitudes(projected_lengths(metric_xy, skeleton), bone_lengths,
                                 np.ones(len(uv)))

    def candidates_for(palm: np.ndarray) -> FingerCandidates:
        palm_dz = np.full(abs_dz.shape, np.nan)
        palm_dz[:, layout.palm_bones] = palm * abs_dz[:, layout.palm_bones]
        states = [walk_rays(rays, depth, skeleton, bone_lengths, sign * palm_dz)[0]
                  for sign in (1.0, -1.0)]
        return perspective_candidates(rays, np.stack(states, axis=1), bone_lengths, layout)

    solution = resolve_signs(metric_xy, abs_dz, bone_lengths, skeleton, hand, candidates_for)
    xyz = _chosen_points(solution, skeleton)
    inconsistency = np.zeros(abs_dz.shape)
    inconsistency[:, child] = np.clip(
        np.linalg.norm(xyz[:, child] - xyz[:, parent], axis=-1) - bone_lengths[child], 0.0,
        None)
    return xyz, inconsistency, solution


def lift_kinematic(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                   camera: Camera, *, hand: str) -> LiftResult:
    """Lift with the hand prior; see the module docstring.

    Parameters are those of :func:`handdb.lifting.lift`.
    """
    image = centred_pixels(uv, camera)
    projected = projected_lengths(image, skeleton)
    scale = smooth_scale(eq6_scale(projected, bone_lengths, rank=SCALE_RANK))
    if camera.model == "pinhole":
        xyz, inconsistency, solution = _lift_pinhole(uv, skeleton, bone_lengths, camera, hand,
                                                     scale)
        scale = np.full(scale.shape, np.nan)
    else:
        abs_dz, inconsistency = depth_magnitudes(projected, bone_lengths, scale)
        solution = resolve_signs(image / scale[:, None, None], abs_dz, bone_lengths,
                                 skeleton, hand)
        z = accumulate_depths(solution.signs * abs_dz, skeleton)
        xyz = orthographic_points(image, scale, z)
    inconsistency[:, skeleton.root] = 0.0
    odds = solution.mirror_log_odds
    ambiguous = odds < np.log(MIRROR_SETTLED_ODDS)
    note = (f"clip-wide mirror not settled: the chosen depth signs are only "
            f"{np.exp(odds):.3g} times as likely as all of them flipped" if ambiguous else "")
    return LiftResult(xyz=xyz, sign_confidence=solution.confidence,
                      length_inconsistency=inconsistency, scale=scale, method="kinematic",
                      mirror_ambiguous=bool(ambiguous), note=note)

