"""The default lifting method, ``kinematic``: depth signs settled with what hands can do.

Per frame, the unsigned depth of every bone follows from eq. 5 at a robust, smoothed scale
(:func:`handdb.lifting.temporal.smooth_scale`). The signs are then chosen in three steps:

1. **Palm.** The palm (wrist, carpometacarpal and long-finger MCP joints) is near rigid and
   near planar: of the sign patterns of its bones, the one whose joints fit a plane best is
   kept, with its mirror image (the palm tilted the other way) as the only alternative.
2. **Fingers.** For each palm state, the palm's normal points to the palmar side as the
   hand's handedness says (``(index MCP − wrist) × (little MCP − wrist)`` for a right hand,
   the opposite for a left one), and each finger's three bones below the palm take one of
   eight sign states. A state is scored by its flexion angles in the finger's plane (the
   plane of the finger's metacarpal and the palm normal): each joint within its range of
   motion, flexing toward the palm, the DIP about 2/3 of the PIP. Scores are log-likelihoods.
3. **Time.** A sign can only change while its bone crosses the image plane, at a local
   minimum of ``|dZ|`` over time; between two minima the evidence of every frame is pooled
   (:mod:`handdb.lifting.temporal`). The palm's tilt is pooled the same way, its evidence
   being the fingers' likelihood under each tilt.

The confidence of each bone's sign is its pooled posterior, discounted by the probability
that the whole clip is mirrored: flipping every sign at once changes only the
flexion-direction evidence, so a clip without clear flexion (a flat hand) cannot settle it,
and the result says so (``mirror_ambiguous``).

With a pinhole camera the signs are found on the weak-perspective view of the clip, then
every joint is placed on its ray at the depth its bone length allows
(:mod:`handdb.lifting.pinhole`).
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from handdb.clip import Camera
from handdb.lifting.geometry import (
    accumulate_depths,
    path_matrix,
    bone_vectors_2d,
    centred_pixels,
    depth_magnitudes,
    eq6_scale,
    orthographic_points,
    projected_lengths,
)
from handdb.lifting.hand_layout import CHAIN_BONES, HandLayout, hand_layout
from handdb.lifting.pinhole import lift_perspective
from handdb.lifting.registry import register
from handdb.lifting.result import LiftResult
from handdb.lifting.temporal import flip_costs, sigmoid, sign_posterior, smooth_scale
from handdb.skeletons import Skeleton

#: Every sign pattern of a finger's three bones, ``(8, 3)``; row ``k`` has bit ``b`` of
#: ``k`` (most significant first) set where bone ``b`` is negative.
SIGN_STATES = np.array(list(itertools.product((1.0, -1.0), repeat=CHAIN_BONES)))

#: Columns summing a finger's state weights where bone 0, 1, 2 is positive, then all.
_MARGINALS = np.concatenate([SIGN_STATES > 0, np.ones((len(SIGN_STATES), 1))], axis=1)

#: The two signs a single bone can take, in the order of each bit of a state.
BONE_SIGNS = np.array([1.0, -1.0])

#: Flexion ranges of a long finger's MCP, PIP and DIP joints, degrees (flexion positive).
LONG_FINGER_RANGE_DEG = np.array([[-30.0, 95.0], [-5.0, 115.0], [-15.0, 95.0]])

#: Flexion ranges of the thumb's three joints below the palm, degrees.
THUMB_RANGE_DEG = np.array([[-45.0, 90.0], [-20.0, 80.0], [-30.0, 95.0]])

#: Softness of a range limit: a violation by this much costs one unit of log-likelihood.
RANGE_SOFTNESS_DEG = 10.0

#: DIP flexion is about this share of PIP flexion in a natural, unloaded finger.
DIP_PIP_RATIO = 2.0 / 3.0

#: Standard deviation of the DIP flexion about ``DIP_PIP_RATIO`` times the PIP's, degrees.
COUPLING_SIGMA_DEG = 25.0

#: How far a finger's joints may go to the back of the palm plane, as a share of the
#: finger's first bone below the palm: about sin 30° for a hyperextended MCP; the thumb
#: stays in front of the palm.
FINGER_DORSAL_MARGIN = 0.5
THUMB_DORSAL_MARGIN = 0.2

#: Softness of that limit, as a share of the first bone.
DORSAL_SOFTNESS = 0.1

#: A weak prior toward relaxed poses: each joint's flexion ~ N(centre, sigma), degrees.
#: It settles the frames where a finger fits either palm tilt, flexed a little or a lot.
COMFORT_CENTRE_DEG = 15.0
COMFORT_SIGMA_DEG = 45.0

#: Ridge added to the palm plane's normal equations (clip units²) so that a palm seen
#: edge-on, its joints on one image line, still has a plane.
PLANE_RIDGE = 1e-9

#: Smallest spread of a bone's frame-to-frame depth change, as a share of its length.
TEMPORAL_FLOOR = 0.05

#: The clip-wide mirror counts as settled when it is this many times less likely.
MIRROR_SETTLED_ODDS = 20.0

HANDEDNESS = {"right": 1.0, "left": -1.0}


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def palm_signs(xy: np.ndarray, abs_dz: np.ndarray, skeleton: Skeleton,
               layout: HandLayout) -> np.ndarray:
    """Sign pattern of the palm's bones that best fits a plane, per frame.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.

    Returns
    -------
    numpy.ndarray
        ``(T, P) float64`` of ±1 for ``layout.palm_bones``; the mirror pattern (all signs
        flipped) fits exactly as well and is the palm's other state. Patterns are
        oriented so that the palm's tilt changes continuously from frame to frame
        (:func:`continuity_signs`): a frame's state 0 continues the previous one's.
    """
    bones = layout.palm_bones
    joints = np.concatenate([[skeleton.root], bones])
    to_depth = path_matrix(skeleton)[np.ix_(joints, bones)]             # (Q, P)
    # Half the patterns suffice: a pattern and its mirror fit the plane equally well.
    combos = np.array(list(itertools.product((1.0, -1.0), repeat=len(bones) - 1)))
    combos = np.concatenate([np.ones((len(combos), 1)), combos], axis=1)
    design = np.concatenate([np.nan_to_num(xy[:, joints]),
                             np.ones((len(xy), len(joints), 1))], axis=-1)  # (T, Q, 3)
    fit = np.linalg.solve(np.swapaxes(design, 1, 2) @ design + PLANE_RIDGE * np.eye(3),
                          np.swapaxes(design, 1, 2))                    # (T, 3, Q)
    residual = np.eye(len(joints)) - design @ fit                        # (T, Q, Q)
    spans = np.nan_to_num(abs_dz[:, bones])[:, None, :] * to_depth       # (T, Q, P)
    quadratic = np.swapaxes(spans, 1, 2) @ residual @ spans              # (T, P, P)
    misfit = np.sum((quadratic @ combos.T) * combos.T, axis=1)          # (T, C)
    best = np.argmin(misfit, axis=1)
    coef = np.einsum("tkq,tqp,tp->tk", fit, spans, combos[best])
    tilt = coef[:, :2]
    return combos[best] * continuity_signs(tilt)[:, None]


def continuity_signs(tilt: np.ndarray) -> np.ndarray:
    """Signs that make a sequence of palm tilts, each known up to its sign, continuous.

    Parameters
    ----------
    tilt
        ``(T, 2) float64``: the gradient of the palm plane's depth over the image plane,
        per frame, with an arbitrary sign.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64`` of ±1 such that consecutive signed tilts never point apart.
    """
    turn = np.ones(len(tilt))
    turn[1:] = np.where(np.sum(tilt[1:] * tilt[:-1], axis=-1) < 0, -1.0, 1.0)
    return np.cumprod(turn)


def finger_log_likelihood(xy: np.ndarray, abs_dz: np.ndarray, palm_z: np.ndarray,
                          bone_lengths: np.ndarray, skeleton: Skeleton, layout: HandLayout,
                          hand: str) -> np.ndarray:
    """Log-likelihood of each finger's sign states under each palm state.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units.
    abs_dz
        ``(T, J) float64``, clip units.
    palm_z
        ``(T, 2, J) float64``: depth of the palm joints relative to the root in palm state
        0 and its mirror, state 1 (other joints: ignored).
    bone_lengths
        ``(J,) float64``, clip units.
    skeleton, layout, hand
        The clip's skeleton, its palm and fingers, and which hand it is.

    Returns
    -------
    anatomy
        ``(T, 2, F, 8) float64``: ranges of motion and DIP-PIP coupling; 0 where a
        finger's bones have no image points.
    comfort
        ``(T, 2, F, 8) float64``: the weak prior toward relaxed poses. It breaks ties but
        is no evidence about the clip-wide mirror, which is judged on ``anatomy`` alone.
    """
    anchors = np.concatenate([[layout.wrist, layout.index_mcp, layout.little_mcp],
                              layout.chain_bases])
    z = palm_z[:, :, anchors]
    points = np.stack([np.broadcast_to(xy[:, None, anchors, 0], z.shape),
                       np.broadcast_to(xy[:, None, anchors, 1], z.shape), z], axis=-1)
    wrist = points[:, :, 0]                                              # (T, 2, 3)
    normal = HANDEDNESS[hand] * _unit(np.cross(points[:, :, 1] - wrist,
                                               points[:, :, 2] - wrist))
    forward = points[:, :, 3:] - wrist[:, :, None]                       # (T, 2, F, 3)
    base_height = np.sum(forward * normal[:, :, None], axis=-1)          # (T, 2, F)
    forward = _unit(forward - np.sum(forward * normal[:, :, None], -1, keepdims=True)
                    * normal[:, :, None])
    bones_2d = bone_vectors_2d(xy, skeleton)[:, layout.chains]          # (T, F, 3, 2)
    depth = abs_dz[:, layout.chains]                                     # (T, F, 3)

    def component(axis: np.ndarray) -> np.ndarray:                      # (T, 2, F, 3, 2)
        planar = (bones_2d[:, None, :, :, 0] * axis[:, :, :, None, 0]
                  + bones_2d[:, None, :, :, 1] * axis[:, :, :, None, 1])
        along_z = depth[:, None] * axis[..., 2:3]
        return planar[..., None] + BONE_SIGNS * along_z[..., None]

    normal_f = np.broadcast_to(normal[:, :, None], forward.shape)
    palmar = component(normal_f)
    # Each bone's angle in the finger plane depends on its own sign only: (..., bone, sign).
    phi = np.arctan2(palmar, component(forward))
    mcp = phi[..., 0, :, None, None]                                     # sign axes (1,2,3)
    pip = _wrap(phi[..., 1, None, :, None] - mcp)
    dip = _wrap(phi[..., 2, None, None, :] - phi[..., 1, None, :, None])
    thumb = layout.is_thumb[:, None, None, None]
    ranges = np.radians(np.where(thumb[..., None, None], THUMB_RANGE_DEG,
                                 LONG_FINGER_RANGE_DEG))                 # (F,1,1,1,3,2)
    softness = np.radians(RANGE_SOFTNESS_DEG)

    def outside(angle: np.ndarray, joint: int) -> np.ndarray:
        low, high = ranges[..., joint, 0], ranges[..., joint, 1]
        return ((np.clip(low - angle, 0.0, None) + np.clip(angle - high, 0.0, None))
                / softness) ** 2

    coupling = (dip - DIP_PIP_RATIO * pip) / np.radians(COUPLING_SIGMA_DEG)
    first_bone = bone_lengths[layout.chains[:, 0]][:, None, None, None]  # (F, 1, 1, 1)
    margin = np.where(thumb, THUMB_DORSAL_MARGIN, FINGER_DORSAL_MARGIN) * first_bone
    knuckle = base_height[..., None, None, None] + palmar[..., 0, :, None, None]
    middle = knuckle + palmar[..., 1, None, :, None]
    end = middle + palmar[..., 2, None, None, :]                         # heights over the palm
    dorsal = sum((np.clip(-height - margin, 0.0, None) / (DORSAL_SOFTNESS * first_bone)) ** 2
                 for height in (knuckle, middle, end))
    cost = (outside(mcp, 0) + outside(pip, 1) + outside(dip, 2) + dorsal
            + np.where(thumb, 0.0, coupling**2))
    centre, spread = np.radians(COMFORT_CENTRE_DEG), np.radians(COMFORT_SIGMA_DEG)
    comfort = (((mcp - centre) / spread) ** 2 + ((pip - centre) / spread) ** 2
               + ((dip - centre) / spread) ** 2)
    states = cost.shape[:-3] + (len(SIGN_STATES),)
    return (np.nan_to_num(-0.5 * cost).reshape(states),
            np.nan_to_num(-0.5 * comfort).reshape(states))


def bone_log_odds(log_likelihood: np.ndarray) -> np.ndarray:
    """Per-bone evidence for the positive sign, marginalised over the finger's states.

    ``(..., 8)`` log-likelihoods in, ``(..., 3)`` log-odds out.
    """
    peak = np.max(log_likelihood, axis=-1, keepdims=True)
    mass = np.exp(log_likelihood - peak) @ _MARGINALS                  # (..., 4)
    with np.errstate(divide="ignore"):
        return np.log(mass[..., :3]) - np.log(mass[..., 3:] - mass[..., :3])


def _log_evidence(log_likelihood: np.ndarray) -> np.ndarray:
    """``log(sum(exp(.)))`` over the last axis, ``(..., 8)`` to ``(...)``."""
    peak = np.max(log_likelihood, axis=-1)
    return peak + np.log(np.exp(log_likelihood - peak[..., None]).sum(axis=-1))


def resolve_signs(xy: np.ndarray, abs_dz: np.ndarray, bone_lengths: np.ndarray,
                  skeleton: Skeleton, hand: str) -> tuple[np.ndarray, np.ndarray, float]:
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

    Returns
    -------
    signs
        ``(T, J) float64`` of ±1 (``+``: the child is farther from the camera); NaN at the
        root.
    confidence
        ``(T, J) float64`` in [0.5, 1]; NaN at the root.
    mirror_log_odds
        Log-odds of the chosen signs against their clip-wide mirror (>= 0).
    """
    layout = hand_layout(skeleton)
    n_frames = len(xy)
    palm = palm_signs(xy, abs_dz, skeleton, layout)                      # (T, P)
    palm_dz = np.zeros((n_frames, skeleton.n_joints))
    palm_dz[:, layout.palm_bones] = palm * abs_dz[:, layout.palm_bones]
    palm_z0 = accumulate_depths(palm_dz, skeleton)
    palm_z = np.stack([palm_z0, -palm_z0], axis=1)
    anatomy, comfort = finger_log_likelihood(xy, abs_dz, palm_z, bone_lengths, skeleton,
                                              layout, hand)
    log_lik = anatomy + comfort

    evidence = _log_evidence(log_lik).sum(axis=-1)                      # (T, 2)
    tilt = np.sqrt(np.nanmean(abs_dz[:, layout.palm_bones] ** 2, axis=1, keepdims=True))
    floor = TEMPORAL_FLOOR * np.nanmean(bone_lengths[layout.palm_bones], keepdims=True)
    palm_odds = sign_posterior(evidence[:, :1] - evidence[:, 1:], flip_costs(tilt, floor))[:, 0]
    state = (palm_odds < 0).astype(np.int64)
    chosen = np.take_along_axis(log_lik, state[:, None, None, None], axis=1)[:, 0]

    chain_dz = abs_dz[:, layout.chains].reshape(n_frames, -1)            # (T, F * 3)
    floor = TEMPORAL_FLOOR * bone_lengths[layout.chains].ravel()
    finger_odds = sign_posterior(bone_log_odds(chosen).reshape(n_frames, -1),
                                 flip_costs(chain_dz, floor)).reshape(chosen.shape[:2] + (3,))
    finger_signs = np.where(finger_odds < 0, -1.0, 1.0)

    # The mirror flips the palm tilt and every finger state at once. Compare each frame's
    # best pose under the chosen tilt with its exact mirror image, on anatomy alone.
    frames = np.arange(n_frames)[:, None]
    fingers = np.arange(len(layout.fingers))[None, :]
    best = np.argmax(chosen, axis=-1)                                    # (T, F)
    own = anatomy[frames, state[:, None], fingers, best]
    mirror = anatomy[frames, 1 - state[:, None], fingers, len(SIGN_STATES) - 1 - best]
    mirror_log_odds = float(np.sum(own - mirror))
    palm_sign = 1.0 - 2.0 * state
    if mirror_log_odds < 0:
        mirror_log_odds, palm_sign, finger_signs = (-mirror_log_odds, -palm_sign,
                                                    -finger_signs)
    p_mirror = sigmoid(-mirror_log_odds)

    signs = np.full((n_frames, skeleton.n_joints), np.nan)
    signs[:, layout.palm_bones] = palm * palm_sign[:, None]
    signs[:, layout.chains] = finger_signs
    confidence = np.full(signs.shape, np.nan)
    confidence[:, layout.palm_bones] = sigmoid(np.abs(palm_odds))[:, None]
    confidence[:, layout.chains] = sigmoid(np.abs(finger_odds))
    confidence = confidence * (1.0 - p_mirror) + (1.0 - confidence) * p_mirror
    return signs, np.clip(confidence, 0.5, 1.0), mirror_log_odds


def _lift_pinhole(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                  camera: Camera, hand: str, weak_scale: np.ndarray,
                  weak_dz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Two perspective walks, the signs settled again between them on metric ``(x, y)``.

    The first walk, seeded by the weak-perspective signs, gives every joint its metric
    image-plane position, free of the weak-perspective distortion of a near hand; the
    signs are then settled again on those positions and the joints walked once more.

    Returns
    -------
    xyz, inconsistency, confidence, mirror_log_odds
        As :func:`walk_rays` and :func:`resolve_signs`.
    """
    xyz, _ = lift_perspective(uv, skeleton, bone_lengths, camera, weak_dz, weak_scale)
    metric_xy = xyz[..., :2] - xyz[:, skeleton.root : skeleton.root + 1, :2]
    abs_dz, _ = depth_magnitudes(projected_lengths(metric_xy, skeleton), bone_lengths,
                                 np.ones(len(xyz)))
    signs, confidence, mirror_log_odds = resolve_signs(metric_xy, abs_dz, bone_lengths,
                                                       skeleton, hand)
    xyz, inconsistency = lift_perspective(uv, skeleton, bone_lengths, camera,
                                          signs * abs_dz, weak_scale)
    return xyz, inconsistency, confidence, mirror_log_odds


def lift_kinematic(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                   camera: Camera, *, hand: str) -> LiftResult:
    """Lift with the hand prior; see the module docstring.

    Parameters are those of :func:`handdb.lifting.lift`.
    """
    image = centred_pixels(uv, camera)
    projected = projected_lengths(image, skeleton)
    scale = smooth_scale(eq6_scale(projected, bone_lengths))
    abs_dz, inconsistency = depth_magnitudes(projected, bone_lengths, scale)
    xy = image / scale[:, None, None]
    signs, confidence, mirror_log_odds = resolve_signs(xy, abs_dz, bone_lengths, skeleton, hand)
    if camera.model == "pinhole":
        xyz, inconsistency, confidence, mirror_log_odds = _lift_pinhole(
            uv, skeleton, bone_lengths, camera, hand, scale, signs * abs_dz)
        scale = np.full(scale.shape, np.nan)
    else:
        xyz = orthographic_points(image, scale, accumulate_depths(signs * abs_dz, skeleton))
    inconsistency[:, skeleton.root] = 0.0
    ambiguous = mirror_log_odds < np.log(MIRROR_SETTLED_ODDS)
    note = (f"clip-wide mirror not settled: the chosen depth signs are only "
            f"{np.exp(mirror_log_odds):.3g} times as likely as all of them flipped"
            if ambiguous else "")
    return LiftResult(xyz=xyz, sign_confidence=confidence,
                      length_inconsistency=inconsistency, scale=scale, method="kinematic",
                      mirror_ambiguous=bool(ambiguous), note=note)


@register("kinematic")
def _kinematic(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray, camera: Camera,
               *, hand: str, **params: Any) -> LiftResult:
    return lift_kinematic(uv, skeleton, bone_lengths, camera, hand=hand, **params)
