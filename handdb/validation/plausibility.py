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
  the frames that hold the bend for more than one frame (:data:`PERSISTENCE_FRAMES`);
* **fit residual**: for a model fit, the distance from the markers to the model's joints,
  frame by frame, below :data:`RESIDUAL_LIMIT_MM` in all but that share of the frames;
* **joint order**: the four knuckles in order across the palm (index, middle, ring,
  little) and the thumb's base on the index side, in all but :data:`ORDER_SHARE_LIMIT` of
  the frames: a ``joint_map`` that swaps two fingers' names gives a hand of plausible bones
  and angles that no hand has.

A clip that fails is not refused: it is stored *flagged* (``clips.flagged`` and
``joints_3d.flagged``), with every reason in words (``clips.flag_reasons``). The
tolerances are wide: the gate catches results no hand could produce (a 222 mm metacarpal,
a middle phalanx longer than the proximal one, fingers bent backwards), not an unusual
hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from handdb.clip import IMAGES, METERS_PER_UNIT, VIDEO
from handdb.hand import anatomy
from handdb.hand.layout import palm_normals, unit_vectors
from handdb.hand.skeletons import FINGERS, Skeleton
from handdb.robust import nan_median, robust_spread
from handdb.vectors import cross, dot, norm

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

#: Frames of a video clip over which a joint's bend must hold to count against the clip:
#: a frame counts when most of the frames centred on it break the range. A hand holds a pose
#: longer than a frame while a detector's glitch (a missed keypoint, a jump to the other
#: hand) lasts one, so a single frame beyond range between plausible ones is noise: the
#: real OpenPose signer's first frame, its thumb undetected and filled, bends the thumb MCP
#: 106 degrees where the next eight frames bend it 5-31. Frames alternating in and out of
#: range still count. Independent images have no neighbours: each counts alone.
PERSISTENCE_FRAMES = 3

#: Largest median distance of a frame's markers from the fitted joints, mm.
RESIDUAL_LIMIT_MM = 10.0

#: Share of the frames that may break the joint order before the clip is flagged: more
#: than half, since a hand seen edge-on lines its knuckles up and noise may swap
#: neighbours there, while swapped names break the order in almost every frame.
ORDER_SHARE_LIMIT = 0.5

#: The knuckles across the palm, from the thumb's side.
KNUCKLES = tuple(f"{finger}_mcp" for finger in FINGERS[1:])

#: A frame's knuckles are out of order when one step between neighbours goes backwards
#: by more than this share of the mean step: neighbours a few millimetres apart may
#: trade places by noise.
ORDER_TOLERANCE = 0.25

#: The thumb joint that stands for its side of the palm, by preference: its MCP, since
#: trackers put the CMC anywhere from the wrist to the palm's centre (DHG's lies nearer
#: the little knuckle than the index one in 98 % of the real capture's frames).
THUMB_BASES = ("thumb_mcp", "thumb_cmc")

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
        Every reason the clip is flagged, in words; empty when nothing is: what no hand
        could produce, and (added by the build, :func:`handdb.gapfill.caveats.fill_caveats`)
        what the input never showed and the hand model placed or left empty.
    rows
        ``(T, J) bool``: the frames and joints at fault: a frame that breaks an angle or
        residual limit, a bone (by its child joint) whose length or constancy is
        implausible, a point placed without evidence.
    """

    reasons: tuple[str, ...]
    rows: np.ndarray

    @property
    def flagged(self) -> bool:
        """The clip carries a reason to doubt it (:attr:`reasons`)."""
        return bool(self.reasons)


def length_bounds_mm(skeleton: Skeleton) -> np.ndarray:
    """``(J, 2)`` bounds of each bone's length an adult hand can have, mm.

    By the bone's child joint; NaN for bones without a proportion.
    """
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
    bounds = length_bounds_mm(skeleton)
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
    per_frame = norm(xyz[:, child] - xyz[:, parent])
    measured = np.isfinite(per_frame).sum(axis=0) >= 2
    median = nan_median(per_frame)
    spread = robust_spread(per_frame)
    changing = measured & (median > 0) & (spread > CONSTANCY_LIMIT * median)
    bones = np.zeros(skeleton.n_joints, dtype=bool)
    bones[child[changing]] = True
    reasons = [f"bone {skeleton.joints[child[k]]} changes length by "
               f"{spread[k] / median[k]:.0%} over the clip (a bone keeps its length)"
               for k in np.flatnonzero(changing)]
    return reasons, bones


def _palm_normals(skeleton: Skeleton, xyz: np.ndarray, hand: str) -> np.ndarray:
    """``(T, 3)`` unit normals of the palm towards its palmar side; NaN where degenerate."""
    wrist, index, little = skeleton.indices(["wrist", "index_mcp", "little_mcp"])
    return palm_normals(xyz[:, wrist], xyz[:, index], xyz[:, little], hand)


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
        lateral = unit_vectors(cross(xyz[:, mcp] - xyz[:, wrist], normal))
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
            turn = cross(before, after)
            cos = dot(before, after)
            if finger == "thumb":
                angles[key] = np.degrees(np.arctan2(norm(turn), cos))
                continue
            angles[key] = np.degrees(np.arctan2(dot(turn, lateral), cos))
    return angles


def persistent_frames(frames: np.ndarray) -> np.ndarray:
    """The frames where most of the :data:`PERSISTENCE_FRAMES` centred on them are set.

    Parameters
    ----------
    frames
        ``(T,) bool``: the frames of a video clip that break a limit.

    Returns
    -------
    numpy.ndarray
        ``(T,) bool``: a running majority, the clip's ends mirrored: a lone frame drops
        out, a run of two or more stays, and frames alternating in and out stay. A clip
        shorter than the window is judged frame by frame (mirroring two frames would swap
        them; scipy mirrors a single frame from memory beyond it).
    """
    if len(frames) < PERSISTENCE_FRAMES:
        return frames.copy()
    return median_filter(frames, size=PERSISTENCE_FRAMES, mode="mirror")


def check_angles(skeleton: Skeleton, xyz: np.ndarray, hand: str, sampling: str = VIDEO
                 ) -> tuple[list[str], np.ndarray]:
    """Frames whose finger joints bend beyond what they can, widened by the tolerance.

    Parameters
    ----------
    skeleton
        The clip's skeleton.
    xyz
        ``(T, J, 3) float64``: the clip's 3D joints, any unit; NaN where absent.
    hand
        ``"left"`` or ``"right"``.
    sampling
        The clip's sampling (:data:`handdb.clip.SAMPLINGS`): a video clip is flagged by
        the share of frames whose bend persists (:func:`persistent_frames`), a clip of
        independent images by the share of images.

    Returns
    -------
    reasons, frames
        The reason found, and ``(T,) bool``: every frame beyond range, persistent or not.
    """
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
    counted = frames if sampling == IMAGES else persistent_frames(frames)
    share = float(counted.mean()) if len(counted) else 0.0
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


def knuckle_order(xyz: np.ndarray, thumb: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Where the four knuckles lie across the palm, frame by frame.

    Parameters
    ----------
    xyz
        ``(T, 4, D) float64``: the index, middle, ring and little MCPs, any unit, ``D`` 2
        or 3; NaN where absent.
    thumb
        ``(T, D) float64``: the thumb's base, which sets the line's orientation (the thumb
        beside the index); ``None`` or NaN: the index and little labels set it.

    Returns
    -------
    position, valid
        ``(T, 4) float64``: each knuckle along the line that fits the four best (their
        first principal axis), increasing away from the thumb; and ``(T,) bool``, the
        frames where that line and its orientation are defined (every knuckle present,
        not all at one point). A swap of two names shows as a step that goes backwards.
    """
    centre = xyz.mean(axis=1)                                          # NaN: one absent
    centred = xyz - centre[:, None]
    present = np.isfinite(centred).all(axis=(1, 2))
    axis = np.zeros((len(xyz), xyz.shape[2]))
    spread = np.zeros(len(xyz))
    if present.any():
        # a frame whose knuckles coincide has no line; its singular value is 0
        _, singular, axes = np.linalg.svd(centred[present], full_matrices=False)
        axis[present], spread[present] = axes[:, 0], singular[:, 0]
    position = np.einsum("tkd,td->tk", np.nan_to_num(centred), axis)
    by_labels = position[:, 3] - position[:, 0]
    if thumb is not None:
        by_thumb = -np.einsum("td,td->t", thumb - centre, axis)
        by_labels = np.where(np.isfinite(by_thumb) & (by_thumb != 0), by_thumb, by_labels)
    direction = np.sign(by_labels)
    valid = present & (spread > 0) & (direction != 0)
    return np.where(valid[:, None], position * direction[:, None], np.nan), valid


def check_joint_order(skeleton: Skeleton, xyz: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Knuckles out of order across the palm, or the thumb on the little finger's side.

    Parameters
    ----------
    skeleton
        The clip's skeleton; without the four MCPs nothing is checked.
    xyz
        ``(T, J, D) float64``: the clip's joints (3D, or 2D image points), any unit; NaN
        where absent.

    Returns
    -------
    reasons, rows
        The reasons found (each naming the joints out of place and what to check), and
        ``(T, J) bool``: the frames breaking the order, at the joints involved.
    """
    rows = np.zeros(xyz.shape[:2], dtype=bool)
    if not all(name in skeleton.joints for name in KNUCKLES):
        return [], rows
    knuckles = skeleton.indices(list(KNUCKLES))
    base = next((name for name in THUMB_BASES if name in skeleton.joints), None)
    thumb = xyz[:, skeleton.index(base)] if base is not None else None
    position, valid = knuckle_order(xyz[:, knuckles], thumb)
    reasons: list[str] = []
    steps = np.diff(position, axis=1)                                   # (T, 3)
    mean_step = np.abs(steps).mean(axis=1, keepdims=True)
    backwards = valid & np.nan_to_num(steps < -ORDER_TOLERANCE * mean_step).any(axis=1)
    if valid.any() and backwards.sum() > ORDER_SHARE_LIMIT * valid.sum():
        orders, counts = np.unique(np.argsort(position[backwards], axis=1), axis=0,
                                   return_counts=True)
        seen = [KNUCKLES[k] for k in orders[np.argmax(counts)]]
        suspects = [name for name, expected in zip(seen, KNUCKLES, strict=True)
                    if name != expected]
        rows[np.ix_(backwards, skeleton.indices(suspects))] = True
        reasons.append(f"the knuckles are out of order across the palm in "
                       f"{backwards.sum() / valid.sum():.0%} of frames: from the thumb they "
                       f"lie {', '.join(seen)} (a hand has {', '.join(KNUCKLES)}); "
                       f"{', '.join(suspects)} look swapped: check the joint_map")
    if base is None or thumb is None:
        return reasons, rows
    index, little = xyz[:, knuckles[0]], xyz[:, knuckles[-1]]
    near_index = norm(thumb - index)
    near_little = norm(thumb - little)
    seen_both = np.isfinite(near_index) & np.isfinite(near_little)
    wrong = seen_both & (near_little < near_index)
    if seen_both.any() and wrong.sum() > ORDER_SHARE_LIMIT * seen_both.sum():
        rows[np.ix_(wrong, skeleton.indices([base, KNUCKLES[0], KNUCKLES[-1]]))] = True
        reasons.append(f"the thumb is on the little finger's side in "
                       f"{wrong.sum() / seen_both.sum():.0%} of frames: {base} lies nearer "
                       f"{KNUCKLES[-1]} than {KNUCKLES[0]}; check the joint_map for a "
                       "swapped thumb, or index and little fingers swapped")
    return reasons, rows


def assess(skeleton: Skeleton, units: str, hand: str, lengths: np.ndarray,
           xyz: np.ndarray | None, residual: np.ndarray | None = None, *,
           n_frames: int = 0, labelled: np.ndarray | None = None,
           sampling: str = VIDEO) -> Verdict:
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
    labelled
        ``(T, J, D) float64``: the points as the input named them, for the joint order
        (a marker clip's markers, which a model fit would put back in order); ``xyz`` by
        default.
    sampling
        The clip's sampling, :data:`handdb.clip.VIDEO` or :data:`handdb.clip.IMAGES`
        (see :func:`check_angles`).
    """
    reasons, bones = check_bone_lengths(skeleton, lengths, units)
    n_frames = n_frames if xyz is None else len(xyz)
    frames = np.zeros(n_frames, dtype=bool)
    joints = np.zeros((n_frames, skeleton.n_joints), dtype=bool)
    named = labelled if labelled is not None else xyz
    if named is not None:
        found, joints = check_joint_order(skeleton, named)
        reasons += found
    if xyz is not None:
        found, unsteady = check_constancy(skeleton, xyz)
        reasons += found
        bones |= unsteady
        found, bent = check_angles(skeleton, xyz, hand, sampling)
        reasons += found
        frames |= bent
    if residual is not None:
        found, far = check_residual(residual, units)
        reasons += found
        frames |= far
    return Verdict(reasons=tuple(reasons), rows=frames[:, None] | bones[None, :] | joints)
