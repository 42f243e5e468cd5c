"""The plausibility gate: could a human hand have produced this clip.

Before a clip is committed its result is checked against what hands are
(:mod:`handdb.hand.anatomy`):

* **bone lengths**: each bone within what adult hands have (its Buchholz proportion of a
  hand length in :data:`HAND_LENGTH_RANGE_MM`, widened by :data:`LENGTH_TOLERANCE`), and
  each finger's phalanges in the proportions X-ray hands show (Chaudhry et al.), widened
  by :data:`SHARE_TOLERANCE`;
* **bone-length constancy**: a bone's length in the 3D result may vary over the clip by
  tracking noise, not by :data:`CONSTANCY_LIMIT` of its length;
* **joint angles**: the flexion of every finger joint in the 3D result within its range of
  motion, widened by :data:`ANGLE_TOLERANCE_DEG`, in all but :data:`FRAME_SHARE_LIMIT` of
  the frames;
* **fit residual**: for a model fit, the distance from the markers to the model's joints,
  frame by frame, below :data:`RESIDUAL_LIMIT_MM` in all but that share of the frames.

A clip that fails is not refused: it is stored *flagged* (``clips.flagged`` and
``joints_3d.flagged``), with every reason in words (``clips.flag_reasons``). The
tolerances are wide: the gate catches results no hand could produce (a 222 mm metacarpal,
a middle phalanx longer than the proximal one, fingers bent backwards), not an unusual
hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.clip import METERS_PER_UNIT
from handdb.hand import anatomy
from handdb.hand.skeletons import FINGERS, Skeleton

#: Hand lengths (distal wrist crease to the middle fingertip) the gate admits, mm: from a
#: small adult hand to a very large one.
HAND_LENGTH_RANGE_MM = (140.0, 240.0)

#: How far a bone may stray beyond its Buchholz proportion of those hand lengths, as a
#: share of it: annotation conventions move a joint by a centimetre or so.
LENGTH_TOLERANCE = 0.35

#: How far a bone from the wrist may reach beyond its proportion, as a share of it:
#: datasets put the wrist point anywhere from the wrist crease to the forearm.
WRIST_TOLERANCE = 1.0

#: How far a phalanx's share of its finger may stray beyond the X-ray hands' range.
SHARE_TOLERANCE = 0.35

#: Largest robust spread (1.4826 MAD) of a bone's length over the clip, as a share of its
#: median length.
CONSTANCY_LIMIT = 0.25

#: How far a joint's flexion may go beyond its range of motion, degrees: lifting and
#: tracking noise bend a finger a little further than it can go.
ANGLE_TOLERANCE_DEG = 35.0

#: Share of the frames that may break an angle or residual limit before the clip is
#: flagged: a few frames of a tracker's glitch are noise, not a hand.
FRAME_SHARE_LIMIT = 0.1

#: Largest median distance of a frame's markers from the fitted joints, mm.
RESIDUAL_LIMIT_MM = 10.0

#: Robust standard deviation of a median absolute deviation.
MAD_TO_SIGMA = 1.4826

#: The hinge joints whose flexion is checked, by the role of the bone that ends at them
#: (the bone after the joint): long fingers' PIP and DIP, the thumb's IP, and each MCP.
_HINGES: dict[str, tuple[tuple[str, str, str], ...]] = {
    "thumb": (("thumb", "mcp", "flexion"), ("thumb", "ip", "flexion")),
    **{f: ((f, "mcp", "flexion"), (f, "pip", "flexion"), (f, "dip", "flexion"))
       for f in FINGERS[1:]},
}


@dataclass(frozen=True)
class Verdict:
    """What the gate found.

    Attributes
    ----------
    reasons
        Every reason the clip is implausible, in words; empty when it is plausible.
    rows
        ``(T, J) bool``: the frames and joints at fault: a frame that breaks an angle or
        residual limit, a bone (by its child joint) whose length or constancy is
        implausible.
    """

    reasons: tuple[str, ...]
    rows: np.ndarray

    @property
    def flagged(self) -> bool:
        """The clip is implausible."""
        return bool(self.reasons)


def _length_bounds_mm(skeleton: Skeleton) -> np.ndarray:
    """``(J, 2)`` bounds of each bone's length, mm; NaN for bones without a proportion."""
    proportion = anatomy.hand_length_proportions(skeleton)
    low, high = HAND_LENGTH_RANGE_MM
    from_wrist = np.array([p >= 0 and skeleton.roles[p] == "wrist" for p in skeleton.parents])
    reach = np.where(from_wrist, 1.0 + WRIST_TOLERANCE, 1.0 + LENGTH_TOLERANCE)
    return np.stack([proportion * low * (1.0 - LENGTH_TOLERANCE),
                     proportion * high * reach], axis=1)


def _phalanx_chain(skeleton: Skeleton, finger: str) -> np.ndarray | None:
    joints = ("ip", "tip") if finger == "thumb" else ("pip", "dip", "tip")
    names = [f"{finger}_{j}" for j in joints]
    if not all(name in skeleton.joints for name in names):
        return None
    return skeleton.indices(names)


def check_bone_lengths(skeleton: Skeleton, lengths: np.ndarray, units: str
                       ) -> tuple[list[str], np.ndarray]:
    """Bone lengths against adult hands and X-ray proportions.

    Parameters
    ----------
    skeleton
        The clip's skeleton.
    lengths
        ``(J,) float64``: the length of the bone ending at each joint, ``units``.
    units
        The clip's length unit.

    Returns
    -------
    reasons, bones
        The reasons found, and ``(J,) bool`` of the bones at fault.
    """
    mm = lengths * METERS_PER_UNIT[units] * 1000.0
    bounds = _length_bounds_mm(skeleton)
    reasons: list[str] = []
    bones = np.zeros(skeleton.n_joints, dtype=bool)
    for j in skeleton.bones[:, 1]:
        low, high = bounds[j]
        if np.isfinite(low) and np.isfinite(mm[j]) and not low <= mm[j] <= high:
            bones[j] = True
            reasons.append(f"bone {skeleton.joints[j]} is {mm[j]:.0f} mm long, outside the "
                           f"{low:.0f}-{high:.0f} mm of adult hands")
    for finger in FINGERS:
        chain = _phalanx_chain(skeleton, finger)
        if chain is None or not np.all(np.isfinite(mm[chain])):
            continue
        share = mm[chain] / mm[chain].sum()
        observed = anatomy.xray_phalanx_ratios(finger)
        low = observed.min(axis=0) * (1.0 - SHARE_TOLERANCE)
        high = observed.max(axis=0) * (1.0 + SHARE_TOLERANCE)
        wrong = (share < low) | (share > high)
        if wrong.any():
            bones[chain[wrong]] = True
            names = ", ".join(skeleton.joints[j] for j in chain[wrong])
            ranges = ", ".join(f"{a:.0%}-{b:.0%}" for a, b in
                               zip(observed.min(axis=0), observed.max(axis=0), strict=True))
            reasons.append(f"the {finger} finger's phalanges are out of proportion ({names}: "
                           f"{', '.join(f'{s:.0%}' for s in share)} of the finger, X-ray "
                           f"hands {ranges})")
    return reasons, bones


def check_constancy(skeleton: Skeleton, xyz: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Bones whose length changes over the clip by more than noise.

    Parameters
    ----------
    skeleton
        The clip's skeleton.
    xyz
        ``(T, J, 3) float64``: the clip's 3D joints, any unit; NaN where absent.
    """
    parent, child = skeleton.bones.T
    per_frame = np.linalg.norm(xyz[:, child] - xyz[:, parent], axis=-1)
    reasons: list[str] = []
    bones = np.zeros(skeleton.n_joints, dtype=bool)
    for k, j in enumerate(child):
        values = per_frame[:, k][np.isfinite(per_frame[:, k])]
        if len(values) < 2:
            continue
        median = np.median(values)
        spread = MAD_TO_SIGMA * np.median(np.abs(values - median))
        if median > 0 and spread > CONSTANCY_LIMIT * median:
            bones[j] = True
            reasons.append(f"bone {skeleton.joints[j]} changes length by {spread / median:.0%} "
                           "over the clip (a bone keeps its length)")
    return reasons, bones


def _palm_normals(skeleton: Skeleton, xyz: np.ndarray, hand: str) -> np.ndarray:
    """``(T, 3)`` unit normals of the palm towards its palmar side."""
    wrist, index, little = skeleton.indices(["wrist", "index_mcp", "little_mcp"])
    normal = np.cross(xyz[:, index] - xyz[:, wrist], xyz[:, little] - xyz[:, wrist])
    if hand == "left":
        normal = -normal
    return normal / np.linalg.norm(normal, axis=-1, keepdims=True)


def flexion_angles(skeleton: Skeleton, xyz: np.ndarray, hand: str
                   ) -> dict[tuple[str, str, str], np.ndarray]:
    """Flexion of every checked joint in every frame, degrees.

    A long finger's joint flexes by the angle from the bone entering it to the bone
    leaving it, signed positive towards the palm: about the finger's lateral axis, its
    metacarpal (wrist to MCP) crossed with the palm normal. The thumb bends about an axis
    of its own, so its joints give the unsigned angle.

    Returns
    -------
    dict
        ``(finger, joint, axis) -> (T,) float64``, NaN where a joint is absent.
    """
    normal = _palm_normals(skeleton, xyz, hand)
    wrist = skeleton.index("wrist")
    angles = {}
    for finger, hinges in _HINGES.items():
        mcp = skeleton.index(f"{finger}_mcp")
        lateral = np.cross(xyz[:, mcp] - xyz[:, wrist], normal)
        lateral /= np.linalg.norm(lateral, axis=-1, keepdims=True)
        for key in hinges:
            name = f"{finger}_{key[1]}"
            if name not in skeleton.joints:
                continue
            j = skeleton.index(name)
            children = skeleton.children(j)
            if len(children) != 1:
                continue
            before = xyz[:, j] - xyz[:, skeleton.parents[j]]
            after = xyz[:, children[0]] - xyz[:, j]
            turn = np.cross(before, after)
            cos = np.sum(before * after, axis=-1)
            if finger == "thumb":
                angles[key] = np.degrees(np.arctan2(np.linalg.norm(turn, axis=-1), cos))
                continue
            angles[key] = np.degrees(np.arctan2(np.sum(turn * lateral, axis=-1), cos))
    return angles


def check_angles(skeleton: Skeleton, xyz: np.ndarray, hand: str
                 ) -> tuple[list[str], np.ndarray]:
    """Frames whose finger joints bend beyond what they can, widened by the tolerance."""
    frames = np.zeros(len(xyz), dtype=bool)
    worst: dict[str, tuple[float, float]] = {}
    for key, angle in flexion_angles(skeleton, xyz, hand).items():
        low, high = anatomy.RANGE_OF_MOTION_DEG[key]
        if key[0] == "thumb":
            low = -180.0  # an unsigned angle: only its size is checked
        excess = np.fmax(low - ANGLE_TOLERANCE_DEG - angle, angle - high - ANGLE_TOLERANCE_DEG)
        bad = np.nan_to_num(excess, nan=-1.0) > 0
        frames |= bad
        if bad.any():
            worst[f"{key[0]} {key[1].upper()}"] = (float(np.nanmax(excess)), float(bad.mean()))
    share = float(frames.mean()) if len(frames) else 0.0
    if share <= FRAME_SHARE_LIMIT:
        return [], frames
    detail = ", ".join(f"{name} by up to {excess:.0f} degrees in {part:.0%} of frames"
                       for name, (excess, part) in sorted(worst.items(),
                                                          key=lambda kv: -kv[1][1])[:3])
    return [f"finger joints bend beyond their range of motion in {share:.0%} of frames "
            f"({detail})"], frames


def check_residual(residual: np.ndarray, units: str) -> tuple[list[str], np.ndarray]:
    """Frames where the markers lie far from the fitted joints.

    Parameters
    ----------
    residual
        ``(T, J) float64``: distance from each visible marker to its joint, ``units``; NaN
        where no marker.
    units
        The clip's length unit.
    """
    mm = residual * METERS_PER_UNIT[units] * 1000.0
    seen = np.isfinite(mm).any(axis=1)
    median = np.full(len(mm), np.nan)
    median[seen] = np.nanmedian(mm[seen], axis=1)
    frames = np.nan_to_num(median, nan=0.0) > RESIDUAL_LIMIT_MM
    share = float(frames.mean()) if len(frames) else 0.0
    if share <= FRAME_SHARE_LIMIT:
        return [], frames
    return [f"the hand model does not fit the markers: {share:.0%} of frames leave them more "
            f"than {RESIDUAL_LIMIT_MM:.0f} mm from the joints (median "
            f"{np.nanmedian(median):.1f} mm)"], frames


def assess(skeleton: Skeleton, units: str, hand: str, lengths: np.ndarray,
           xyz: np.ndarray | None, residual: np.ndarray | None = None, *,
           n_frames: int = 0) -> Verdict:
    """Check a clip's result against what hands can be.

    Parameters
    ----------
    skeleton
        The clip's skeleton.
    units, hand
        The clip's length unit and hand.
    lengths
        ``(J,) float64``: the clip's bone lengths, ``units`` (NaN at the root).
    xyz
        ``(T, J, 3) float64``: its 3D joints, ``units``, NaN where absent; ``None`` when it
        has none.
    residual
        ``(T, J) float64`` marker residuals of a model fit, ``units``; ``None`` otherwise.
    n_frames
        The clip's frames, when ``xyz`` is ``None``.
    """
    reasons, bones = check_bone_lengths(skeleton, lengths, units)
    n_frames = n_frames if xyz is None else len(xyz)
    frames = np.zeros(n_frames, dtype=bool)
    if xyz is not None:
        found, unsteady = check_constancy(skeleton, xyz)
        reasons += found
        bones |= unsteady
        found, bent = check_angles(skeleton, xyz, hand)
        reasons += found
        frames |= bent
    if residual is not None:
        found, far = check_residual(residual, units)
        reasons += found
        frames |= far
    return Verdict(reasons=tuple(reasons), rows=frames[:, None] | bones[None, :])
