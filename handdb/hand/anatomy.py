"""What human hands are: joint ranges of motion, couplings, proportions and the mean palm.

Everything here is a published figure or derived from one, and is the one place handdb
keeps it: the kinematic model (:mod:`handdb.hand.model`), the synthetic hands
(:mod:`handdb.hand.population`), the lifting prior, marker fitting and the plausibility
gate all read their numbers from this module.

Conventions: a right hand in the *hand frame*, origin at the wrist, ``x`` to the radial
(thumb) side, ``y`` distal (towards the middle finger's knuckle), ``z`` out of the palm.
Flexion is positive towards the palm, abduction positive away from the middle finger (for
the middle finger: towards the thumb; for the thumb: away from the palm, palmar
abduction), twist positive clockwise seen from the fingertip of a right hand. Joints are
named by role (:mod:`handdb.hand.skeletons`): ``cmc``, ``mcp``, ``pip``, ``dip``, ``ip``.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pyarrow.compute as pc

from handdb.hand.skeletons import FINGERS, Skeleton

#: The three axes of a joint's angles, in the order a three-axis joint applies them
#: (intrinsic z-x-y: abduction about the bone's flexion-side axis, flexion about its
#: lateral axis, twist about the bone).
AXES: tuple[str, ...] = ("abduction", "flexion", "twist")

#: Axes each articulating joint turns about.
JOINT_AXES: dict[str, tuple[str, ...]] = {
    "cmc": AXES, "mcp": AXES, "pip": ("flexion",), "dip": ("flexion",), "ip": ("flexion",),
}

#: The joint at the start of the bone that ends at a joint of each role: its angles move
#: that bone. Thumb: CMC moves the metacarpal (ending at the MCP), MCP the proximal
#: phalanx (ending at the IP), IP the distal phalanx. Long fingers: MCP, PIP, DIP.
MOVING_JOINT: dict[tuple[str, str], str] = {
    ("thumb", "mcp"): "cmc", ("thumb", "ip"): "mcp", ("thumb", "tip"): "ip",
    **{(finger, end): start for finger in FINGERS[1:]
       for end, start in (("pip", "mcp"), ("dip", "pip"), ("tip", "dip"))},
}

#: Active range of motion of every joint axis, degrees ``(lower, upper)``, keyed by
#: ``(finger, joint, axis)``. Flexion of the long fingers and the thumb's MCP and IP
#: follow the American Academy of Orthopaedic Surgeons' norms (*Joint Motion: Method of
#: Measuring and Recording*, 1965): MCP 90 flexion with up to 45 hyperextension (a
#: relaxed, loose-jointed hand reaches 30; 20 is kept), PIP 0-110 (Hoppenfeld 1976
#: averages 110), DIP 0-90 with 10 hyperextension, thumb MCP 0-55 with 10
#: hyperextension, thumb IP 0-80 with 15 hyperextension. Thumb CMC: 15 flexion, 20
#: extension, 70 palmar abduction (AAOS). Long-finger abduction allows the widest spread
#: between neighbouring fingers measured in young adults (about 17 degrees index-middle,
#: 14 middle-ring, 32 ring-little). Twist and the thumb MCP's side motion have no
#: clinical norm; they are kept small.
RANGE_OF_MOTION_DEG: dict[tuple[str, str, str], tuple[float, float]] = {
    ("thumb", "cmc", "abduction"): (-10.0, 70.0),
    ("thumb", "cmc", "flexion"): (-20.0, 50.0),
    ("thumb", "cmc", "twist"): (-20.0, 20.0),
    ("thumb", "mcp", "abduction"): (-10.0, 10.0),
    ("thumb", "mcp", "flexion"): (-10.0, 55.0),
    ("thumb", "mcp", "twist"): (-10.0, 10.0),
    ("thumb", "ip", "flexion"): (-15.0, 80.0),
    **{(finger, "mcp", "flexion"): (-20.0, 90.0) for finger in FINGERS[1:]},
    **{(finger, "mcp", "twist"): (-10.0, 10.0) for finger in FINGERS[1:]},
    **{(finger, "pip", "flexion"): (0.0, 110.0) for finger in FINGERS[1:]},
    **{(finger, "dip", "flexion"): (-10.0, 90.0) for finger in FINGERS[1:]},
    ("index", "mcp", "abduction"): (-10.0, 20.0),
    ("middle", "mcp", "abduction"): (-10.0, 10.0),
    ("ring", "mcp", "abduction"): (-10.0, 15.0),
    ("little", "mcp", "abduction"): (-10.0, 30.0),
}

#: In a natural, unloaded finger the DIP flexes about two thirds as much as the PIP
#: (Rijpkema & Girard 1991, "Computer animation of knowledge-based human grasping").
DIP_PIP_COUPLING = 2.0 / 3.0


#: Sense of a positive abduction about a bone's flexion-side axis (the palm normal for the
#: long fingers): away from the middle finger, turning radially (negative about the
#: palmar normal) for the thumb, index and middle fingers, ulnarly for the ring and little.
ABDUCTION_SIGN: dict[str, float] = {
    "thumb": -1.0, "index": -1.0, "middle": -1.0, "ring": 1.0, "little": 1.0,
}


def range_of_motion(finger: str, joint: str, axis: str) -> tuple[float, float]:
    """The active range of one joint axis, radians ``(lower, upper)``."""
    lower, upper = RANGE_OF_MOTION_DEG[(finger, joint, axis)]
    return float(np.radians(lower)), float(np.radians(upper))


# -- proportions ----------------------------------------------------------------------

#: Buchholz, Armstrong & Goldstein (1992), "Anthropometric data for describing the
#: kinematics of the human hand", *Ergonomics* 35(3):261-273: each kinematic segment's
#: length as a proportion of hand length (distal wrist crease to the tip of the middle
#: finger), fitted on radiographs and photographs of adult hands. Per finger, from the
#: root: thumb metacarpal (CMC to MCP), proximal, distal; fingers metacarpal, proximal,
#: middle, distal.
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


@cache
def xray_phalanx_ratios(finger: str) -> np.ndarray:
    """Relative phalanx lengths of ``finger`` on each X-ray image of Chaudhry et al.

    Read from the paper's Table 1, which handdb ships.

    Returns
    -------
    (M, K) float64
        Per image (rows, the paper's Figure 1a-1e), each phalanx's length over the
        finger's total length, proximal to distal; rows sum to 1. Read-only.
    """
    from handdb.lengths.ratios import relative_lengths, table1_measurements

    relative = relative_lengths(table1_measurements())
    rows = relative.filter(pc.equal(relative.column("finger"), finger)).sort_by(
        [("image_id", "ascending"), ("segment", "ascending")])
    n_images = len(pc.unique(rows.column("image_id")))
    ratios = rows.column("ratio").to_numpy().reshape(n_images, -1)
    ratios.flags.writeable = False
    return ratios


@cache
def segment_proportions(finger: str) -> tuple[float, ...]:
    """The average hand's segments of ``finger`` as proportions of hand length.

    The metacarpal and the phalanges' total are Buchholz's (:data:`BUCHHOLZ_1992`); the
    total is split in the mean X-ray shares of Chaudhry et al.
    (:func:`xray_phalanx_ratios`). Buchholz's own split ends the distal segment where the
    bone ends; the X-ray shares put more of the finger into it, as annotations do that
    mark the fingertip on the skin.

    Returns
    -------
    tuple of float
        Metacarpal, then the phalanges proximal to distal, as :data:`BUCHHOLZ_1992`.
    """
    metacarpal, *phalanges = BUCHHOLZ_1992[finger]
    shares = xray_phalanx_ratios(finger).mean(axis=0)
    return (metacarpal, *map(float, sum(phalanges) * shares / shares.sum()))


@cache
def _proportions() -> dict[tuple[str, str, str], float]:
    """Every bone's proportion keyed by (finger, parent role, child role).

    The segments are :func:`segment_proportions`. No proportion is published for the span
    from the wrist to a finger's knuckle, which skeletons such as MediaPipe's use as one
    bone: for the middle finger it is hand length less its three phalanges; for the other
    fingers that span scaled by their metacarpal over the middle metacarpal.
    """
    table = {}
    for finger in FINGERS:
        spans = _THUMB_SPANS if finger == "thumb" else _FINGER_SPANS
        table.update({(finger, *span): c for span, c in
                      zip(spans, segment_proportions(finger), strict=True)})
    wrist_to_middle_knuckle = 1.0 - sum(BUCHHOLZ_1992["middle"][1:])
    for finger in FINGERS[1:]:
        scale = BUCHHOLZ_1992[finger][0] / BUCHHOLZ_1992["middle"][0]
        table[(finger, "wrist", "mcp")] = wrist_to_middle_knuckle * scale
    return table


def hand_length_proportions(skeleton: Skeleton) -> np.ndarray:
    """Length of the bone ending at each joint as a proportion of hand length.

    Returns
    -------
    np.ndarray
        ``(J,) float64``, dimensionless; NaN for the root and for bones without a
        published proportion (wrist to thumb base, palm centre, palm fold).
    """
    proportions = _proportions()
    return np.array([
        np.nan if parent < 0 else proportions.get(
            (finger, skeleton.roles[parent], role), np.nan)
        for parent, finger, role in zip(skeleton.parents, skeleton.fingers, skeleton.roles,
                                        strict=True)
    ])


#: Hand length (distal wrist crease to the middle fingertip) of an average adult, mm.
MEAN_HAND_LENGTH_MM = 185.0

# -- the mean palm ----------------------------------------------------------------------
# Joint centres of the average right hand at rest, in the hand frame, as fractions of
# hand length. The carpometacarpal joints sit just distal of the wrist, their spread
# giving the usual knuckle spacing (about 18 mm on a 185 mm hand) and the knuckle arc
# (middle highest, little lowest); each metacarpal then runs its Buchholz length at its
# angle. The metacarpal heads form the transverse arch, the middle one its dorsal apex,
# the little one most palmar. The thumb's carpometacarpal joint lies on the palmar side
# of the plane of the wrist and the knuckles, its metacarpal pointing radially, distally
# and out of that plane.

#: Carpometacarpal joint centres ``(x, y, z)``, fractions of hand length.
CMC_POSITION: dict[str, tuple[float, float, float]] = {
    "thumb": (0.13, 0.09, 0.06), "index": (0.04, 0.075, 0.0), "middle": (0.0, 0.075, 0.0),
    "ring": (-0.035, 0.07, 0.0), "little": (-0.065, 0.065, 0.0),
}

#: Direction of each metacarpal in the palm plane, degrees from ``+y`` towards ``+x``.
METACARPAL_ANGLE_DEG: dict[str, float] = {
    "thumb": 35.0, "index": 9.5, "middle": 0.0, "ring": -10.0, "little": -21.0,
}

#: Elevation of each metacarpal out of the palm plane towards the palm, degrees: the
#: transverse arch at the metacarpal heads, and the thumb's metacarpal standing off it.
METACARPAL_ELEVATION_DEG: dict[str, float] = {
    "thumb": 15.0, "index": 2.5, "middle": 0.0, "ring": 1.5, "little": 5.0,
}

#: Direction of each extended finger beyond its MCP, degrees from ``+y`` towards ``+x``.
FINGER_ANGLE_DEG: dict[str, float] = {
    "thumb": 35.0, "index": 5.0, "middle": 0.0, "ring": -5.0, "little": -12.0,
}

#: Angle between the thumb's flexion side and the palm normal, degrees: the thumb is
#: pronated relative to the fingers, so it curls across the palm, not straight up.
THUMB_PRONATION_DEG = 60.0

#: Joints inside the palm, as a fraction of the way from the wrist to the middle MCP: the
#: palm centre of ``dhg22`` (DHG's sensor puts it about half way) and the palm fold of
#: ``thesis21`` (its Maya hand puts it about two thirds of the way).
PALM_CENTER_FRACTION = 0.5
PALM_FOLD_FRACTION = 2.0 / 3.0
