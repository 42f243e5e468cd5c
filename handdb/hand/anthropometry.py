"""Bone lengths as proportions of hand length, for bones nothing else measures.

Source: Buchholz, Armstrong & Goldstein (1992), "Anthropometric data for describing the
kinematics of the human hand", *Ergonomics* 35(3):261-273. They measured joint centres
on radiographs and photographs of adult hands and fitted each kinematic segment's
length as a proportion of hand length (distal wrist crease to the tip of the middle
finger). The coefficients below are theirs: the metacarpal (thumb: carpometacarpal to
metacarpophalangeal joint), proximal, middle and distal segment of each digit.

The paper gives no proportion for the span from the wrist to a finger's knuckle, which
skeletons such as MediaPipe's use as one bone. It is derived here: for the middle
finger, hand length less its three phalanges; for the other fingers, that span scaled
by their metacarpal over the middle metacarpal. Bones with no proportion at all (wrist
to thumb base, palm centre, palm fold) are left out: a clip needs them from another
source.
"""

from __future__ import annotations

import numpy as np

from handdb.hand.skeletons import Skeleton

#: Buchholz et al. (1992): segment length / hand length, per finger, from the root.
#: Thumb: metacarpal, proximal, distal; fingers: metacarpal, proximal, middle, distal.
BUCHHOLZ_1992: dict[str, tuple[float, ...]] = {
    "thumb": (0.251, 0.196, 0.158),
    "index": (0.374, 0.265, 0.143, 0.097),
    "middle": (0.373, 0.277, 0.170, 0.108),
    "ring": (0.336, 0.259, 0.165, 0.107),
    "little": (0.295, 0.206, 0.117, 0.093),
}

#: Roles of the joints each coefficient of :data:`BUCHHOLZ_1992` spans, from the root.
_THUMB_SPANS = (("cmc", "mcp"), ("mcp", "ip"), ("ip", "tip"))
_FINGER_SPANS = (("cmc", "mcp"), ("mcp", "pip"), ("pip", "dip"), ("dip", "tip"))


def _proportions() -> dict[tuple[str, str, str], float]:
    table = {}
    for finger, coefficients in BUCHHOLZ_1992.items():
        spans = _THUMB_SPANS if finger == "thumb" else _FINGER_SPANS
        table.update({(finger, *span): c for span, c in zip(spans, coefficients, strict=True)})
    wrist_to_middle_knuckle = 1.0 - sum(BUCHHOLZ_1992["middle"][1:])
    for finger in ("index", "middle", "ring", "little"):
        scale = BUCHHOLZ_1992[finger][0] / BUCHHOLZ_1992["middle"][0]
        table[(finger, "wrist", "mcp")] = wrist_to_middle_knuckle * scale
    return table


#: Bone length / hand length keyed by (finger, parent role, child role).
HAND_LENGTH_PROPORTIONS: dict[tuple[str, str, str], float] = _proportions()


def hand_length_proportions(skeleton: Skeleton) -> np.ndarray:
    """Length of the bone ending at each joint as a proportion of hand length.

    Returns
    -------
    np.ndarray
        ``(J,) float64``, dimensionless; NaN for the root and for bones without a
        published proportion.
    """
    return np.array([
        np.nan if parent < 0 else HAND_LENGTH_PROPORTIONS.get(
            (finger, skeleton.roles[parent], role), np.nan)
        for parent, finger, role in zip(skeleton.parents, skeleton.fingers, skeleton.roles,
                                        strict=True)
    ])
