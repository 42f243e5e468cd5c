"""The thesis's depth reconstruction (§3.5–3.6, §4.1.1.4): ``thesis``, ``thesis-nocheck``.

Every frame gets the scale of eq. 6 (the smallest scale giving every bone a real depth);
every bone's depth span follows from eq. 5, walking from the root to the tips. Each bone
takes the thesis's positive direction, except that with the reflective-ambiguity check
(``thesis``) a fingertip turns back toward the palm when the inner angle at its finger's
PIP joint, measured in the (y, z) plane, lies in (0°, 90°].

Sign convention: the thesis's Maya scene has z growing toward the viewer, and its positive
direction (PIP and DIP "greater than" their parents) is that of a finger flexing toward a
palm that faces the camera. In handdb's camera frame (z away from the camera) that is
``−z``; a fingertip turned "toward the palm" goes ``+z``.

Two departures from the appendix program, both deliberate: the scale is eq. 6 per frame
(the program takes the smallest ratio and then fixes ``s = 1``), and a negative
discriminant is clamped to zero and reported as a length inconsistency (the program grows
the length by 0.001 until the root is real). Depths hang from the skeleton's own tree, so
on ``thesis21`` the wrist hangs from the palm fold (the program pairs it with the thumb
MCP).
"""

from __future__ import annotations

import numpy as np

from handdb.clip import Camera
from handdb.hand.skeletons import Skeleton
from handdb.lifting.geometry import (
    accumulate_depths,
    centred_pixels,
    depth_magnitudes,
    eq6_scale,
    orthographic_points,
    projected_lengths,
)
from handdb.lifting.result import LiftResult

#: The thesis's positive depth direction in handdb's camera frame (toward the camera).
THESIS_POSITIVE_Z = -1.0

#: A fingertip turns back toward the palm when the PIP's inner angle is in (0°, this].
TIP_TURN_MAX_ANGLE_DEG = 90.0

#: Fingers the reflective-ambiguity rule applies to (the thumb has no PIP).
RULE_FINGERS = ("index", "middle", "ring", "little")


def rule_chains(skeleton: Skeleton) -> np.ndarray:
    """Joints ``(A, B, C, D)`` = (MCP, PIP, DIP, tip) of each finger the rule covers.

    Returns
    -------
    numpy.ndarray
        ``(K, 4) int64``; fingers lacking one of the four roles are left out.
    """
    chains = []
    for finger in RULE_FINGERS:
        roles = {skeleton.roles[j]: j for j in skeleton.finger_chain(finger)}
        if all(r in roles for r in ("mcp", "pip", "dip", "tip")):
            chains.append([roles["mcp"], roles["pip"], roles["dip"], roles["tip"]])
    return np.array(chains, dtype=np.int64).reshape(-1, 4)


def inner_angle_deg(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Inner angle ABC at ``b`` between the segments to ``a`` and ``c``, degrees.

    Parameters
    ----------
    a, b, c
        ``(..., D) float64`` points (the thesis uses their (y, z) coordinates).

    Returns
    -------
    numpy.ndarray
        ``(...) float64`` in [0, 180]; NaN where a segment has zero length.
    """
    ba, bc = a - b, c - b
    norms = np.linalg.norm(ba, axis=-1) * np.linalg.norm(bc, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        cosine = np.sum(ba * bc, axis=-1) / norms
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def tip_turns(y: np.ndarray, z: np.ndarray, chains: np.ndarray) -> np.ndarray:
    """Where the rule turns each covered fingertip toward the palm.

    Parameters
    ----------
    y, z
        ``(T, J) float64``, clip units: image-plane y and depth with every bone positive.
    chains
        ``(K, 4)`` joints from :func:`rule_chains`.

    Returns
    -------
    numpy.ndarray
        ``(T, K) bool``: the PIP's inner angle in the (y, z) plane is in (0°, 90°].
    """
    yz = np.stack([y, z], axis=-1)
    angle = inner_angle_deg(yz[:, chains[:, 0]], yz[:, chains[:, 1]], yz[:, chains[:, 2]])
    return (angle > 0.0) & (angle <= TIP_TURN_MAX_ANGLE_DEG)


def lift_thesis(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                camera: Camera, *, hand: str, check: bool = True) -> LiftResult:
    """Lift with the thesis's method (``check``: with its reflective-ambiguity rule).

    Parameters are those of :func:`handdb.lifting.lift`; ``hand`` is unused (the thesis
    assumes the palm faces the camera).
    """
    image = centred_pixels(uv, camera)
    projected = projected_lengths(image, skeleton)
    scale = eq6_scale(projected, bone_lengths)
    abs_dz, inconsistency = depth_magnitudes(projected, bone_lengths, scale)
    signed = THESIS_POSITIVE_Z * abs_dz
    if check:
        chains = rule_chains(skeleton)
        z_positive = accumulate_depths(signed, skeleton)
        turned = tip_turns(image[..., 1] / scale[:, None], z_positive, chains)
        tips = chains[:, 3]
        signed[:, tips] = np.where(turned, -signed[:, tips], signed[:, tips])
    z = accumulate_depths(signed, skeleton)
    inconsistency[:, skeleton.root] = 0.0
    return LiftResult(
        xyz=orthographic_points(image, scale, z),
        sign_confidence=np.full(abs_dz.shape, np.nan),
        length_inconsistency=inconsistency,
        scale=scale,
        method="thesis" if check else "thesis-nocheck",
    )


def lift_thesis_nocheck(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                        camera: Camera, *, hand: str) -> LiftResult:
    """Lift with the thesis's method without its reflective-ambiguity rule."""
    return lift_thesis(uv, skeleton, bone_lengths, camera, hand=hand, check=False)
