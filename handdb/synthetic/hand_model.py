"""A procedural hand: bone lengths from anthropometry and X-ray ratios, and its rest pose.

The hand frame
--------------
Every hand is built as a *right* hand in a right-handed frame with its origin at the
skeleton's root joint (the wrist; the palm fold for ``thesis21``):

* ``x`` points to the radial (thumb) side,
* ``y`` points from the wrist to the middle-finger MCP (distal),
* ``z = x × y`` points out of the palm (palmar side).

In the rest pose the palm and the extended fingers lie in the plane ``z = 0`` and fingers
flex toward ``+z``. A left hand is the mirror image of the right one through the ``y–z``
plane (``x -> -x``): its thumb lies toward ``-x`` and its palm still faces ``+z``.

Where the numbers come from
---------------------------
* Metacarpal and total finger lengths as fractions of hand length (wrist crease to the tip
  of the middle finger) follow the link-length proportions of Buchholz, Armstrong &
  Goldstein (1992), *Ergonomics* 35(3) (:data:`handdb.hand.anthropometry.BUCHHOLZ_1992`).
* The split of a finger's length among its phalanges follows the X-ray measurements of
  Chaudhry, You, Jin & Zhang (seed document ``002``, Table 1, shipped as
  :func:`handdb.lengths.ratios.table1_measurements`): the average hand has the mean relative
  length of each phalanx over the five X-ray hands, a sampled subject a random mixture
  of the five.
* The layout of the carpometacarpal joints and the resting splay of the rays are
  hand-chosen to reproduce typical MCP spacing (about 18 mm for a 185 mm hand) and the
  MCP arc (middle highest, little lowest).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import pyarrow.compute as pc

from handdb.errors import BoneLengthError, SkeletonError
from handdb.hand.anthropometry import BUCHHOLZ_1992
from handdb.hand.skeletons import FINGERS, Skeleton, load_skeleton
from handdb.lengths.ratios import relative_lengths, table1_measurements

#: Hand length (wrist crease to middle fingertip) of an average adult, mm.
DEFAULT_HAND_LENGTH_MM = 185.0


@cache
def xray_ratios(finger: str) -> np.ndarray:
    """Relative phalanx lengths of ``finger`` on each X-ray image of Chaudhry et al.

    Returns
    -------
    (M, K) float64
        Per image (rows, the paper's Figure 1a-1e), each phalanx's length over the
        finger's total length, proximal to distal; rows sum to 1.
    """
    relative = relative_lengths(table1_measurements())
    rows = relative.filter(pc.equal(relative.column("finger"), finger)).sort_by(
        [("image_id", "ascending"), ("segment", "ascending")])
    n_images = len(pc.unique(rows.column("image_id")))
    return rows.column("ratio").to_numpy().reshape(n_images, -1)


#: Metacarpal length (CMC to MCP joint centre), fraction of hand length.
METACARPAL_FRACTION: dict[str, float] = {f: c[0] for f, c in BUCHHOLZ_1992.items()}

#: Sum of the phalanges (MCP joint to fingertip), fraction of hand length.
FINGER_FRACTION: dict[str, float] = {f: sum(c[1:]) for f, c in BUCHHOLZ_1992.items()}

#: Carpometacarpal joint centres in the palm plane, ``(x, y)`` as fractions of hand length.
CMC_POSITION: dict[str, tuple[float, float]] = {
    "thumb": (0.13, 0.09), "index": (0.04, 0.075), "middle": (0.0, 0.075),
    "ring": (-0.035, 0.07), "little": (-0.065, 0.065),
}

#: Direction of each metacarpal, degrees from ``+y`` toward the thumb side (``+x``).
METACARPAL_ANGLE_DEG: dict[str, float] = {
    "thumb": 35.0, "index": 9.5, "middle": 0.0, "ring": -10.0, "little": -21.0,
}

#: Direction of each extended finger beyond its MCP, degrees from ``+y`` toward ``+x``.
FINGER_ANGLE_DEG: dict[str, float] = {
    "thumb": 35.0, "index": 5.0, "middle": 0.0, "ring": -5.0, "little": -12.0,
}

#: Angle between the thumb's flexion side and the palm normal, degrees: the thumb is
#: pronated relative to the fingers, so it curls across the palm, not straight up.
THUMB_PRONATION_DEG = 60.0

#: Joints inside the palm, as a fraction of the way from the wrist to the middle MCP:
#: the palm centre of ``dhg22`` (DHG's sensor puts it about half way) and the palm fold
#: of ``thesis21`` (its Maya hand puts it about two thirds of the way).
PALM_CENTER_FRACTION = 0.5
PALM_FOLD_FRACTION = 2.0 / 3.0

#: Per-subject variation of segment lengths: relative standard deviation (a few percent,
#: the spread of adult metacarpal and finger proportions) and the clip at two sigma.
LENGTH_VARIATION = 0.03
VARIATION_CLIP_SIGMA = 2.0

#: Dirichlet concentration of the mixture of X-ray hands a subject's phalanx ratios are
#: drawn from; below 1 favours mixtures close to one X-ray hand, keeping the X-ray spread.
XRAY_MIXTURE_CONCENTRATION = 0.5

PALM_NORMAL = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class HandModel:
    """A hand of fixed proportions: a skeleton, its bone lengths and its rest pose.

    Attributes
    ----------
    skeleton
        The joint tree.
    hand
        ``"right"`` or ``"left"``.
    units
        Length unit of ``bone_lengths`` (``"mm"``; ``"cm"`` for the thesis's Maya hand).
    bone_lengths
        ``(J,) float64``: length of the bone ending at each joint; NaN for the root.
    bone_frames
        ``(J, 3, 3) float64``: the rest orientation of the bone ending at each joint, in
        the right-hand frame (see module docstring); columns are the bone's lateral axis,
        its direction (parent to child) and its flexion side. The root's frame is the
        identity. For a left hand the same frames are used and the result mirrored.
    """

    skeleton: Skeleton
    hand: str
    units: str
    bone_lengths: np.ndarray
    bone_frames: np.ndarray

    @property
    def rest_pose(self) -> np.ndarray:
        """Joint positions at rest in the hand's own frame, ``(J, 3) float64``, ``units``.

        The root is at the origin; a left hand is mirrored (``x -> -x``).
        """
        offsets = np.nan_to_num(self.bone_lengths)[:, None] * self.bone_frames[:, :, 1]
        pose = np.zeros_like(offsets)
        for joint, parent in enumerate(self.skeleton.parents):
            if parent >= 0:
                pose[joint] = pose[parent] + offsets[joint]
        return pose * mirror_sign(self.hand)

    @property
    def hand_length(self) -> float:
        """Wrist to middle fingertip at rest, ``units``."""
        pose = self.rest_pose
        tip, wrist = self.skeleton.index("middle_tip"), self.skeleton.index("wrist")
        return float(np.linalg.norm(pose[tip] - pose[wrist]))

    def bone_length_dict(self) -> dict[str, float]:
        """Bone lengths as ``{child joint: length}`` (``units``), as a sidecar holds them."""
        return {
            name: float(self.bone_lengths[child])
            for name, child in zip(self.skeleton.bone_names, self.skeleton.bones[:, 1],
                                   strict=True)
        }


def mirror_sign(hand: str) -> np.ndarray:
    """Per-axis sign taking right-hand coordinates to ``hand``'s, ``(3,) float64``."""
    if hand not in ("right", "left"):
        raise ValueError(f"hand must be 'right' or 'left', got {hand!r}")
    return np.array([-1.0 if hand == "left" else 1.0, 1.0, 1.0])


@dataclass(frozen=True)
class HandProportions:
    """A subject's hand proportions, each as a fraction of hand length.

    Attributes
    ----------
    metacarpal
        Metacarpal length per finger.
    finger
        Total phalanx length per finger (MCP joint to fingertip).
    phalanx_ratios
        Relative phalanx lengths per finger, proximal to distal, summing to 1.
    palm_breadth
        Scale of the lateral (``x``) spread of the carpometacarpal joints, 1 on average.
    """

    metacarpal: dict[str, float]
    finger: dict[str, float]
    phalanx_ratios: dict[str, np.ndarray]
    palm_breadth: float = 1.0

    @classmethod
    def mean(cls) -> HandProportions:
        """Return the average hand: tabulated fractions and the mean X-ray ratios."""
        return cls(
            metacarpal=dict(METACARPAL_FRACTION),
            finger=dict(FINGER_FRACTION),
            phalanx_ratios={f: xray_ratios(f).mean(axis=0) for f in FINGERS},
        )

    @classmethod
    def sample(cls, rng: np.random.Generator) -> HandProportions:
        """One subject: every length varies by a few percent, ratios as on the X-rays.

        Metacarpal and finger lengths and the palm breadth are scaled by
        ``1 + LENGTH_VARIATION * n`` with ``n`` standard normal, clipped at
        ``VARIATION_CLIP_SIGMA``. A finger's phalanx ratios are a random convex mixture
        (Dirichlet weights, concentration ``XRAY_MIXTURE_CONCENTRATION``) of the X-ray
        hands' ratios, so they sum to 1 and each stays within the X-ray minimum and
        maximum.
        """
        def factor() -> float:
            n = np.clip(rng.standard_normal(), -VARIATION_CLIP_SIGMA, VARIATION_CLIP_SIGMA)
            return float(1.0 + LENGTH_VARIATION * n)

        ratios = {}
        for finger in FINGERS:
            observed = xray_ratios(finger)
            weights = rng.dirichlet(np.full(len(observed), XRAY_MIXTURE_CONCENTRATION))
            ratios[finger] = weights @ observed
        return cls(
            metacarpal={f: v * factor() for f, v in METACARPAL_FRACTION.items()},
            finger={f: v * factor() for f, v in FINGER_FRACTION.items()},
            phalanx_ratios=ratios,
            palm_breadth=factor(),
        )


def _unit(angle_deg: float) -> np.ndarray:
    """Return the palm-plane unit vector ``angle_deg`` from ``+y`` toward ``+x``."""
    a = np.radians(angle_deg)
    return np.array([np.sin(a), np.cos(a), 0.0])


def canonical_layout(proportions: HandProportions) -> dict[str, np.ndarray]:
    """Rest positions of every canonical joint of a right hand, in hand lengths.

    Parameters
    ----------
    proportions
        The subject's proportions.

    Returns
    -------
    dict[str, (3,) float64]
        Position of each canonical joint (every joint name any preset uses), in the hand
        frame, in units of hand length; the wrist is at the origin.
    """
    layout = {"wrist": np.zeros(3)}
    for finger in FINGERS:
        cx, cy = CMC_POSITION[finger]
        cmc = np.array([cx * proportions.palm_breadth, cy, 0.0])
        mcp = cmc + proportions.metacarpal[finger] * _unit(METACARPAL_ANGLE_DEG[finger])
        phalanges = proportions.finger[finger] * proportions.phalanx_ratios[finger]
        beyond = np.cumsum(phalanges)[:, None] * _unit(FINGER_ANGLE_DEG[finger])
        names = ("ip", "tip") if finger == "thumb" else ("pip", "dip", "tip")
        layout[f"{finger}_cmc"] = cmc
        layout[f"{finger}_mcp"] = mcp
        layout.update({f"{finger}_{n}": mcp + b for n, b in zip(names, beyond, strict=True)})
    layout["palm"] = PALM_CENTER_FRACTION * layout["middle_mcp"]
    layout["palm_fold"] = PALM_FOLD_FRACTION * layout["middle_mcp"]
    return layout


def _flexion_side(skeleton: Skeleton, joint: int) -> np.ndarray:
    """Return the direction a bone bends toward when it flexes, at rest (right hand)."""
    if skeleton.fingers[joint] != "thumb" or skeleton.roles[joint] == "cmc":
        return PALM_NORMAL
    along = _unit(FINGER_ANGLE_DEG["thumb"])
    across_palm = np.cross(PALM_NORMAL, along)
    beta = np.radians(THUMB_PRONATION_DEG)
    return np.cos(beta) * PALM_NORMAL + np.sin(beta) * across_palm


def _bone_frames(skeleton: Skeleton, layout: dict[str, np.ndarray]) -> np.ndarray:
    """Rest frames ``(J, 3, 3)`` of every bone of ``skeleton`` from a layout's directions."""
    frames = np.tile(np.eye(3), (skeleton.n_joints, 1, 1))
    for joint, parent in enumerate(skeleton.parents):
        if parent < 0:
            continue
        direction = layout[skeleton.joints[joint]] - layout[skeleton.joints[parent]]
        direction = direction / np.linalg.norm(direction)
        side = _flexion_side(skeleton, joint)
        side = side - side @ direction * direction
        side = side / np.linalg.norm(side)
        frames[joint] = np.stack([np.cross(direction, side), direction, side], axis=1)
    return frames


def _check_canonical(skeleton: Skeleton, layout: dict[str, np.ndarray]) -> None:
    unknown = [j for j in skeleton.joints if j not in layout]
    if unknown:
        raise SkeletonError(
            f"skeleton '{skeleton.name}' has joints the hand model cannot place: "
            f"{', '.join(unknown)} (known: {', '.join(sorted(layout))})"
        )


def make_hand(
    skeleton: str = "mediapipe21",
    hand_length_mm: float = DEFAULT_HAND_LENGTH_MM,
    seed: int | None = None,
    hand: str = "right",
) -> HandModel:
    """Build a hand of anatomically plausible proportions.

    Parameters
    ----------
    skeleton
        Preset name (``mediapipe21``, ``dhg22``, ``thesis21``).
    hand_length_mm
        Wrist crease to middle fingertip, mm (adult range roughly 160-210).
    seed
        ``None`` gives the average hand; an integer draws one subject whose segment
        lengths differ from the average by a few percent (see
        :meth:`HandProportions.sample`).
    hand
        ``"right"`` or ``"left"``.

    Returns
    -------
    HandModel
        Bone lengths in mm.
    """
    if not np.isfinite(hand_length_mm) or hand_length_mm <= 0:
        raise ValueError(f"hand_length_mm must be a positive number, got {hand_length_mm}")
    mirror_sign(hand)
    skel = load_skeleton(skeleton)
    proportions = (HandProportions.mean() if seed is None
                   else HandProportions.sample(np.random.default_rng(seed)))
    layout = canonical_layout(proportions)
    _check_canonical(skel, layout)
    lengths = np.full(skel.n_joints, np.nan)
    parent, child = skel.bones.T
    points = np.stack([layout[j] for j in skel.joints])
    lengths[child] = hand_length_mm * np.linalg.norm(points[child] - points[parent], axis=1)
    return HandModel(skeleton=skel, hand=hand, units="mm", bone_lengths=lengths,
                     bone_frames=_bone_frames(skel, layout))


def thesis_hand(hand: str = "right") -> HandModel:
    """Build the thesis's Maya hand: ``thesis21`` with exactly its appendix lengths.

    Bone lengths are the skeleton's ``reference_lengths`` (Maya units, taken as cm); bone
    directions at rest are those of the average procedural hand.
    """
    mirror_sign(hand)
    skel = load_skeleton("thesis21")
    layout = canonical_layout(HandProportions.mean())
    lengths = np.full(skel.n_joints, np.nan)
    for name, length in skel.reference_lengths.items():
        lengths[skel.index(name)] = length
    missing = [skel.joints[c] for c in skel.bones[:, 1] if np.isnan(lengths[c])]
    if missing:
        raise BoneLengthError(f"thesis21 reference lengths miss bones {', '.join(missing)}")
    return HandModel(skeleton=skel, hand=hand, units="cm", bone_lengths=lengths,
                     bone_frames=_bone_frames(skel, layout))
