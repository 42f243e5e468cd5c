"""A hand's shape at rest: where its joints are when the fingers are straight.

:class:`HandShape` holds the rest position of every canonical joint (every joint name a
skeleton preset uses, plus each thumb's carpometacarpal joint) in the hand frame of
:mod:`handdb.hand.anatomy`, for a right hand. A skeleton's bones, lengths and rest
directions follow from it (:meth:`HandShape.bone_lengths`, :meth:`HandShape.positions`),
so one shape serves ``mediapipe21``, ``dhg22`` and ``thesis21`` alike; the kinematic
model (:mod:`handdb.hand.model`) moves it. :func:`mean_shape` is the average adult hand;
:mod:`handdb.hand.population` draws others.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from handdb.errors import ParameterError, SkeletonError
from handdb.hand import anatomy
from handdb.hand.skeletons import FINGERS, Skeleton

#: Names of the phalanx joints beyond each finger's MCP, base to tip.
PHALANX_JOINTS: dict[str, tuple[str, ...]] = {
    "thumb": ("ip", "tip"), **{f: ("pip", "dip", "tip") for f in FINGERS[1:]},
}

#: The palm's normal in the hand frame: towards the palmar side.
PALM_NORMAL = np.array([0.0, 0.0, 1.0])


def direction(azimuth_deg: float, elevation_deg: float = 0.0) -> np.ndarray:
    """A unit vector in the hand frame, ``(3,) float64``.

    ``azimuth_deg`` turns it from ``+y`` towards ``+x``; ``elevation_deg`` raises it
    towards ``+z`` (the palm).
    """
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    return np.array([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)])


@dataclass(frozen=True)
class HandShape:
    """The rest pose of one right hand.

    Attributes
    ----------
    points
        ``{canonical joint: (3,) float64}``: rest positions in the hand frame (origin at
        the wrist, ``x`` radial, ``y`` distal, ``z`` palmar), ``units``. Fingers are
        straight; the thumb points along its metacarpal.
    units
        Length unit of ``points``.
    thumb_pronation_deg
        Angle between the thumb's flexion side and the palm normal, degrees.
    """

    points: Mapping[str, np.ndarray]
    units: str = "mm"
    thumb_pronation_deg: float = anatomy.THUMB_PRONATION_DEG

    def point(self, joint: str) -> np.ndarray:
        """Rest position of ``joint``, ``(3,) float64``."""
        try:
            return np.array(self.points[joint], dtype=np.float64)
        except KeyError:
            raise SkeletonError(f"the hand shape has no joint '{joint}' (its joints: "
                                f"{', '.join(sorted(self.points))})") from None

    def positions(self, skeleton: Skeleton) -> np.ndarray:
        """Rest positions of ``skeleton``'s joints, ``(J, 3) float64``, hand frame."""
        return np.stack([self.point(j) for j in skeleton.joints])

    def bone_lengths(self, skeleton: Skeleton) -> np.ndarray:
        """Length of the bone ending at each joint of ``skeleton``, ``(J,)``; NaN at the root."""
        points = self.positions(skeleton)
        lengths = np.full(skeleton.n_joints, np.nan)
        parent, child = skeleton.bones.T
        lengths[child] = np.linalg.norm(points[child] - points[parent], axis=-1)
        return lengths

    @property
    def hand_length(self) -> float:
        """Wrist to middle fingertip at rest, ``units``."""
        return float(np.linalg.norm(self.point("middle_tip") - self.point("wrist")))

    def flexion_side(self, finger: str) -> np.ndarray:
        """The direction a finger's bones bend towards when they flex, at rest, ``(3,)``.

        The palm normal for the long fingers; for the thumb the normal turned by the
        thumb's pronation about its metacarpal, towards the palm's ulnar side.
        """
        if finger != "thumb":
            return PALM_NORMAL.copy()
        along = self.point("thumb_mcp") - self.point("thumb_cmc")
        along /= np.linalg.norm(along)
        across = np.cross(PALM_NORMAL, along)
        across /= np.linalg.norm(across)
        beta = np.radians(self.thumb_pronation_deg)
        side = np.cos(beta) * PALM_NORMAL + np.sin(beta) * across
        side = side - side @ along * along
        return side / np.linalg.norm(side)

    def scaled(self, factor: float, units: str | None = None) -> HandShape:
        """The same shape ``factor`` times as large (in ``units``, default the same)."""
        return HandShape({j: factor * p for j, p in self.points.items()},
                         units or self.units, self.thumb_pronation_deg)

    def with_bone_lengths(self, skeleton: Skeleton, lengths: np.ndarray) -> HandShape:
        """The shape with ``skeleton``'s bones at ``lengths``, each along its rest direction.

        Parameters
        ----------
        skeleton
            The skeleton ``lengths`` follows.
        lengths
            ``(J,) float64``: length of the bone ending at each joint, ``units``; NaN keeps
            a bone as it is.

        Returns
        -------
        HandShape
            The skeleton's joints moved so its bones have those lengths, walking from its
            root (which stays); a joint keeps its offset from its parent where the length
            is NaN. Joints the skeleton lacks stay where they were.
        """
        lengths = np.asarray(lengths, dtype=np.float64)
        if lengths.shape != (skeleton.n_joints,):
            raise SkeletonError(f"lengths must be ({skeleton.n_joints},) for skeleton "
                                f"'{skeleton.name}', got {lengths.shape}")
        old = self.positions(skeleton)
        new = old.copy()
        for parent, child in skeleton.bones:
            offset = old[child] - old[parent]
            if np.isfinite(lengths[child]):
                offset *= lengths[child] / np.linalg.norm(offset)
            new[child] = new[parent] + offset
        points = dict(self.points)
        points.update({joint: new[j] for j, joint in enumerate(skeleton.joints)})
        return HandShape(points, self.units, self.thumb_pronation_deg)


def shape_from_layout(metacarpal_mm: Mapping[str, float], phalanges_mm: Mapping[str, np.ndarray],
                      *, cmc_mm: Mapping[str, np.ndarray],
                      metacarpal_angle_deg: Mapping[str, float] = anatomy.METACARPAL_ANGLE_DEG,
                      metacarpal_elevation_deg: Mapping[str, float] =
                      anatomy.METACARPAL_ELEVATION_DEG,
                      finger_angle_deg: Mapping[str, float] = anatomy.FINGER_ANGLE_DEG,
                      wrist_mm: np.ndarray | None = None,
                      thumb_pronation_deg: float = anatomy.THUMB_PRONATION_DEG) -> HandShape:
    """Lay a right hand out from its bones, in millimetres.

    Parameters
    ----------
    metacarpal_mm
        Metacarpal length (CMC to MCP) per finger.
    phalanges_mm
        Phalanx lengths per finger, base to tip (two for the thumb, three otherwise).
    cmc_mm
        Carpometacarpal joint centre ``(3,)`` per finger, hand frame.
    metacarpal_angle_deg, metacarpal_elevation_deg
        Each metacarpal's direction: azimuth from ``+y`` towards ``+x`` and elevation
        towards the palm.
    finger_angle_deg
        Each long finger's direction beyond its MCP, in the palm plane; the thumb's
        phalanges continue along its metacarpal.
    wrist_mm
        Where the wrist point lies, hand frame (default the origin); skeletons differ in
        where they put it.
    thumb_pronation_deg
        See :class:`HandShape`.
    """
    points = {"wrist": np.zeros(3) if wrist_mm is None else np.asarray(wrist_mm, float)}
    for finger in FINGERS:
        cmc = np.asarray(cmc_mm[finger], dtype=np.float64)
        along = direction(metacarpal_angle_deg[finger], metacarpal_elevation_deg[finger])
        mcp = cmc + metacarpal_mm[finger] * along
        beyond = along if finger == "thumb" else direction(finger_angle_deg[finger])
        reach = np.cumsum(np.asarray(phalanges_mm[finger], dtype=np.float64))
        if finger == "thumb":
            points["thumb_cmc"] = cmc
        points[f"{finger}_mcp"] = mcp
        points.update({f"{finger}_{name}": mcp + r * beyond
                       for name, r in zip(PHALANX_JOINTS[finger], reach, strict=True)})
    middle = points["middle_mcp"] - points["wrist"]
    points["palm"] = points["wrist"] + anatomy.PALM_CENTER_FRACTION * middle
    points["palm_fold"] = points["wrist"] + anatomy.PALM_FOLD_FRACTION * middle
    return HandShape(points, "mm", thumb_pronation_deg)


def mean_shape(hand_length_mm: float = anatomy.MEAN_HAND_LENGTH_MM) -> HandShape:
    """The average adult right hand, in millimetres.

    Its segments are :func:`handdb.hand.anatomy.segment_proportions` of its length, its
    palm the mean palm of :mod:`handdb.hand.anatomy`.
    """
    if not np.isfinite(hand_length_mm) or hand_length_mm <= 0:
        raise ParameterError(f"hand_length_mm must be a positive number, got {hand_length_mm}")
    proportions = {finger: anatomy.segment_proportions(finger) for finger in FINGERS}
    return shape_from_layout(
        metacarpal_mm={f: hand_length_mm * c[0] for f, c in proportions.items()},
        phalanges_mm={f: hand_length_mm * np.array(c[1:]) for f, c in proportions.items()},
        cmc_mm={f: hand_length_mm * np.array(p) for f, p in anatomy.CMC_POSITION.items()},
    )
