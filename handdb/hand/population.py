"""Populations of hands: shapes drawn as different as real hands and real annotations are.

Real hands differ in size, proportions and palm shape, and datasets differ in where they
put a joint (a wrist point at the styloid line or in the carpus, a knuckle at the joint
centre or on its crease, a thumb base anywhere from the palm plane to 25 mm in front of
it). :func:`sample_shape` draws one right hand from all of that; every spread below is a
named constant, in hand lengths or degrees.

Bone lengths follow Buchholz et al. (1992) within :data:`LENGTH_SPREAD`, with each finger's
phalanx split a random mixture of the five X-ray hands of Chaudhry et al. (their Table 1),
so the split stays within the X-ray minimum and maximum.
"""

from __future__ import annotations

import numpy as np

from handdb.hand import anatomy
from handdb.hand.shape import HandShape, shape_from_layout
from handdb.hand.skeletons import FINGERS

#: Adult hand length (distal wrist crease to the middle fingertip), mm: mean, standard
#: deviation and the range kept (adult men average about 190, women about 173).
HAND_LENGTH_MM = (182.0, 11.0, (155.0, 215.0))

#: Relative standard deviation of each metacarpal and finger length about Buchholz's
#: proportion, and the clip of every normal draw, in standard deviations.
LENGTH_SPREAD = 0.04
CLIP_SIGMA = 2.0

#: Dirichlet concentration of the mixture of X-ray hands a phalanx split is drawn from;
#: below 1 favours mixtures close to one X-ray hand, keeping the X-ray spread.
XRAY_MIXTURE_CONCENTRATION = 0.5

#: Relative standard deviation of the palm's breadth (the carpometacarpal spread in x).
PALM_BREADTH_SPREAD = 0.07

#: Range of the transverse arch's depth, as a multiple of the mean arch.
ARCH_RANGE = (0.0, 2.5)

#: Where the thumb's carpometacarpal joint lies, hand lengths, about the mean palm's:
#: standard deviations in x and y, and the range of its height in front of the palm plane.
THUMB_BASE_SPREAD_XY = 0.02
THUMB_BASE_HEIGHT_RANGE = (-0.01, 0.14)

#: Standard deviations of the thumb metacarpal's azimuth and elevation and of the thumb's
#: pronation, degrees.
THUMB_ANGLE_SPREAD_DEG = 8.0
THUMB_PRONATION_SPREAD_DEG = 12.0

#: Standard deviation of the scale of the long fingers' fan (their rest directions about
#: the middle finger's), and of each one's own direction, degrees; neighbouring fingers
#: rest 5-7 degrees apart, so the fan scales as a whole and never crosses.
FAN_SPREAD = 0.15
FINGER_ANGLE_SPREAD_DEG = 1.0

#: Where an annotation puts the wrist point, hand lengths from the joint-centre wrist:
#: ranges in x (radial), y (distal) and z (palmar).
WRIST_POINT_RANGE = ((-0.03, 0.03), (-0.06, 0.06), (-0.03, 0.05))

#: Standard deviation of where an annotation puts the knuckles off the palm plane, hand
#: lengths (a joint centre, a crease, the dorsal surface).
KNUCKLE_HEIGHT_SPREAD = 0.015


def _normal(rng: np.random.Generator, sigma: float) -> float:
    return float(sigma * np.clip(rng.standard_normal(), -CLIP_SIGMA, CLIP_SIGMA))


def sample_hand_length(rng: np.random.Generator) -> float:
    """One adult hand length, mm, from :data:`HAND_LENGTH_MM`."""
    mean, sigma, (low, high) = HAND_LENGTH_MM
    return float(np.clip(mean + sigma * rng.standard_normal(), low, high))


def sample_shape(rng: np.random.Generator, hand_length_mm: float | None = None) -> HandShape:
    """Draw one right hand: size, proportions, palm shape and annotation conventions.

    Parameters
    ----------
    rng
        The random generator; equal states give equal hands.
    hand_length_mm
        The hand's length, mm; drawn from :data:`HAND_LENGTH_MM` when ``None``.

    Returns
    -------
    HandShape
        In millimetres.
    """
    length = sample_hand_length(rng) if hand_length_mm is None else float(hand_length_mm)
    proportions = anatomy.BUCHHOLZ_1992
    breadth = 1.0 + _normal(rng, PALM_BREADTH_SPREAD)
    arch = rng.uniform(*ARCH_RANGE)
    fan = 1.0 + _normal(rng, FAN_SPREAD)
    metacarpal, phalanges, cmc = {}, {}, {}
    azimuth, elevation, finger_angle = {}, {}, {}
    for finger in FINGERS:
        coefficients = proportions[finger]
        metacarpal[finger] = length * coefficients[0] * (1.0 + _normal(rng, LENGTH_SPREAD))
        total = length * sum(coefficients[1:]) * (1.0 + _normal(rng, LENGTH_SPREAD))
        observed = anatomy.xray_phalanx_ratios(finger)
        weights = rng.dirichlet(np.full(len(observed), XRAY_MIXTURE_CONCENTRATION))
        phalanges[finger] = total * (weights @ observed)
        x, y, z = anatomy.CMC_POSITION[finger]
        if finger == "thumb":
            azimuth[finger] = anatomy.METACARPAL_ANGLE_DEG[finger] + _normal(
                rng, THUMB_ANGLE_SPREAD_DEG)
            finger_angle[finger] = azimuth[finger]
        else:
            azimuth[finger] = fan * anatomy.METACARPAL_ANGLE_DEG[finger] + _normal(
                rng, FINGER_ANGLE_SPREAD_DEG)
            finger_angle[finger] = fan * anatomy.FINGER_ANGLE_DEG[finger] + _normal(
                rng, FINGER_ANGLE_SPREAD_DEG)
        if finger == "thumb":
            x += _normal(rng, THUMB_BASE_SPREAD_XY)
            y += _normal(rng, THUMB_BASE_SPREAD_XY)
            z = rng.uniform(*THUMB_BASE_HEIGHT_RANGE)
            elevation[finger] = (anatomy.METACARPAL_ELEVATION_DEG[finger]
                                 + _normal(rng, THUMB_ANGLE_SPREAD_DEG))
        else:
            x *= breadth
            elevation[finger] = arch * anatomy.METACARPAL_ELEVATION_DEG[finger]
        cmc[finger] = length * np.array([x, y, z])
    shape = shape_from_layout(
        metacarpal, phalanges, cmc_mm=cmc, metacarpal_angle_deg=azimuth,
        metacarpal_elevation_deg=elevation, finger_angle_deg=finger_angle,
        wrist_mm=length * np.array([rng.uniform(*r) for r in WRIST_POINT_RANGE]),
        thumb_pronation_deg=anatomy.THUMB_PRONATION_DEG + _normal(
            rng, THUMB_PRONATION_SPREAD_DEG))
    knuckle_height = length * _normal(rng, KNUCKLE_HEIGHT_SPREAD)
    points = dict(shape.points)
    for finger in FINGERS[1:]:
        for joint in ("mcp", "pip", "dip", "tip"):
            points[f"{finger}_{joint}"] = points[f"{finger}_{joint}"] + (0.0, 0.0,
                                                                         knuckle_height)
    return HandShape(points, "mm", shape.thumb_pronation_deg)
