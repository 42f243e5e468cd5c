"""The length of every bone of a clip, and where it came from.

Depth reconstruction needs every bone's length in the clip's units. Each bone takes its
length from the first of these sources that gives one (most direct measurement first,
population statistics last):

1. ``given``: the sidecar's ``bone_lengths``, what the user measured on the subject.
2. ``truth``: the median over frames of the bone's length in the ground-truth 3D
   positions, robust to frames where a joint jumps.
3. ``calibrated``: subject calibration of a marker clip's fit
   (:func:`handdb.markers.calibration.calibrate`).
4. ``reference_frame``: the thesis's reference hand (Nopvichai 2009, section 3.2): in the
   frame where the hand is most stretched in 2D, taken to be flat and facing the camera,
   2D lengths are proportional to 3D lengths (orthographic projection; a pinhole camera
   too, the hand lying at one depth), so one known length gives the scale of the rest.
5. ``ratios``: a finger's phalanges from one or more of its known phalanges and the
   X-ray relative lengths of Chaudhry et al. (:mod:`handdb.lengths.ratios`).
6. ``anthropometric``: bones as proportions of hand length (Buchholz et al. 1992,
   :mod:`handdb.hand.anatomy`), the hand length estimated from the bones known so far.

Sources 4-6 only scale what 1-3 give: a clip with no given lengths, no ground truth and
no markers has no length scale at all and raises :class:`BoneLengthError`; so does a
clip left with a bone no source can give.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import Clip
from handdb.errors import BoneLengthError
from handdb.hand.anatomy import hand_length_proportions
from handdb.hand.skeletons import Skeleton, frame_bone_lengths
from handdb.lengths.ratios import bone_ratios, joint_ratios, table1_measurements
from handdb.store import tables

#: Every source of a bone length, in order of precedence.
SOURCES: tuple[str, ...] = (
    "given", "truth", "calibrated", "reference_frame", "ratios", "anthropometric",
)


@dataclass(frozen=True)
class BoneLengths:
    """Every bone of a skeleton with its length and where that came from.

    Attributes
    ----------
    skeleton
        The skeleton; arrays follow its joint order, a bone named by its child joint.
    units
        Length unit of ``lengths`` and ``residuals``.
    lengths
        ``(J,) float64``: length of the bone ending at each joint; NaN for the root.
    sources
        ``(J,)``: the source of each length (one of :data:`SOURCES`), ``None`` for the
        root.
    details
        ``(J,)``: how each length was derived, ``None`` for the root.
    residuals
        ``(J,) float64``: calibration residual (median absolute deviation of the
        per-frame length from the estimate), NaN where not calibrated.
    n_frames
        ``(J,) int64``: frames the length was measured over, 0 where not measured.
    """

    skeleton: Skeleton
    units: str
    lengths: np.ndarray
    sources: tuple[str | None, ...]
    details: tuple[str | None, ...]
    residuals: np.ndarray
    n_frames: np.ndarray


def most_stretched_frame(uv: np.ndarray, skeleton: Skeleton) -> int:
    """Pick the reference frame: the one showing the hand most stretched in 2D.

    Among the frames in which the most bones are seen, the one whose 2D bones are
    longest in total.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64`` image positions, pixels; NaN where not observed.
    skeleton
        The skeleton of the joint axis.

    Returns
    -------
    int
        Index of the frame.
    """
    lengths = frame_bone_lengths(uv, skeleton)
    seen = np.isfinite(lengths).sum(axis=1)
    total = np.where(seen == seen.max(), np.nansum(lengths, axis=1), -np.inf)
    return int(np.argmax(total))


def scale_reference_frame(uv_frame: np.ndarray, skeleton: Skeleton,
                          known: np.ndarray) -> tuple[np.ndarray, float]:
    """Lengths of the bones seen in a reference frame, scaled by the known lengths.

    Parameters
    ----------
    uv_frame
        ``(J, 2) float64`` image positions in the reference frame, pixels; NaN where
        not observed.
    skeleton
        The skeleton of the joint axis.
    known
        ``(J,) float64`` lengths known so far, clip units; NaN where unknown.

    Returns
    -------
    lengths
        ``(J,) float64``, clip units: each bone seen in the frame, NaN elsewhere (all
        NaN when no known bone is seen).
    scale
        Clip units per pixel: the median over the known bones seen of known length
        over 2D length; NaN when there is none.
    """
    pixels = frame_bone_lengths(uv_frame[None], skeleton)[0]
    anchors = np.isfinite(known) & (pixels > 0)
    if not anchors.any():
        return np.full(skeleton.n_joints, np.nan), np.nan
    scale = float(np.median(known[anchors] / pixels[anchors]))
    return pixels * scale, scale


def lengths_from_ratios(skeleton: Skeleton, known: np.ndarray,
                        mean_ratio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Phalanges from the known phalanges of their finger and the X-ray ratios.

    Each known phalanx ``k`` of a finger estimates the finger's total length as
    ``known_k / ratio_k``; their mean times each ratio gives every phalanx.

    Parameters
    ----------
    skeleton
        The skeleton of the joint axis.
    known
        ``(J,) float64`` lengths known so far; NaN where unknown.
    mean_ratio
        ``(J,) float64`` mean relative length of each phalanx in its finger
        (:func:`handdb.lengths.ratios.bone_ratios`); NaN for other bones.

    Returns
    -------
    lengths
        ``(J,) float64``: every phalanx of a finger with a known phalanx; NaN elsewhere.
    finger_total
        ``(J,) float64``: the estimated total length of the finger of each such bone.
    """
    fingers = np.array(skeleton.fingers)
    anchors = np.isfinite(known) & np.isfinite(mean_ratio)
    same_finger = fingers[:, None] == fingers[None, :]
    votes = same_finger & anchors[None, :]
    estimates = np.where(anchors, known / np.where(anchors, mean_ratio, 1.0), 0.0)
    with np.errstate(invalid="ignore"):
        finger_total = (votes @ estimates) / votes.sum(axis=1)
    return finger_total * mean_ratio, finger_total


def lengths_from_hand_length(skeleton: Skeleton,
                             known: np.ndarray) -> tuple[np.ndarray, float]:
    """Bones as published proportions of a hand length estimated from the known bones.

    Parameters
    ----------
    skeleton
        The skeleton of the joint axis.
    known
        ``(J,) float64`` lengths known so far; NaN where unknown.

    Returns
    -------
    lengths
        ``(J,) float64``: every bone with a proportion; all NaN when no known bone has one.
    hand_length
        The median over known bones of length over proportion; NaN when none.
    """
    proportion = hand_length_proportions(skeleton)
    anchors = np.isfinite(known) & np.isfinite(proportion)
    if not anchors.any():
        return np.full(skeleton.n_joints, np.nan), np.nan
    hand_length = float(np.median(known[anchors] / proportion[anchors]))
    return proportion * hand_length, hand_length


class _Ledger:
    """The lengths found so far for one skeleton; each bone keeps its first source."""

    def __init__(self, skeleton: Skeleton) -> None:
        self.skeleton = skeleton
        self.lengths = np.full(skeleton.n_joints, np.nan)
        self.sources: list[str | None] = [None] * skeleton.n_joints
        self.details: list[str | None] = [None] * skeleton.n_joints
        self.residuals = np.full(skeleton.n_joints, np.nan)
        self.n_frames = np.zeros(skeleton.n_joints, dtype=np.int64)

    def missing(self) -> np.ndarray:
        """``(J,) bool``: the bones still without a length."""
        return np.isnan(self.lengths) & (self.skeleton.parents >= 0)

    def add(self, source: str, lengths: np.ndarray, detail: Callable[[int], str], *,
            residuals: np.ndarray | None = None, n_frames: np.ndarray | None = None) -> None:
        """Take ``lengths`` (``(J,)``, NaN where none) for the bones still missing."""
        new = self.missing() & np.isfinite(lengths) & (lengths > 0)
        for j in np.flatnonzero(new):
            self.lengths[j] = lengths[j]
            self.sources[j] = source
            self.details[j] = detail(int(j))
            if residuals is not None:
                self.residuals[j] = residuals[j]
            if n_frames is not None:
                self.n_frames[j] = n_frames[j]


def clip_bone_lengths(clip: Clip, ratios: pa.Table | None = None) -> BoneLengths:
    """Give every bone of a clip's skeleton a length, by the precedence of the module.

    Parameters
    ----------
    clip
        The clip: its sidecar's ``bone_lengths``, its ``truth`` and its 2D tracks.
    ratios
        Table ``joint_ratios`` (cohort ``all`` is used); ``None`` or an empty table uses
        the paper's Table 1.

    Returns
    -------
    BoneLengths
        In the clip's units.

    Raises
    ------
    BoneLengthError
        When the clip has no length scale (no given lengths, no truth, no markers), or
        some bone can be had from no source; the message names the bones and the fix.
    """
    skeleton, spec = clip.skeleton, clip.spec
    if ratios is None or ratios.num_rows == 0:
        ratios = joint_ratios(table1_measurements())
    ledger = _Ledger(skeleton)

    given = np.array([spec.bone_lengths.get(j, np.nan) for j in skeleton.joints])
    sidecar = Path(spec.path).name
    ledger.add("given", given, lambda j: f"bone_lengths in {sidecar}")
    if clip.truth is not None:
        per_frame = frame_bone_lengths(clip.truth, skeleton)
        n_frames = np.isfinite(per_frame).sum(axis=0)
        seen = n_frames > 0
        median = np.full(skeleton.n_joints, np.nan)
        median[seen] = np.nanmedian(per_frame[:, seen], axis=0)
        ledger.add("truth", median, lambda j: f"median over {n_frames[j]} frames of the "
                   "ground truth", n_frames=n_frames)
    if not np.isfinite(ledger.lengths).any():
        raise BoneLengthError(
            f"clip '{clip.clip_id}': no bone length to scale the hand by: the sidecar "
            "gives no bone_lengths, and the clip has no ground truth and no 3D markers; "
            f"add at least one bone's length (e.g. \"index_pip\") to bone_lengths in "
            f"{spec.path}")

    uv = np.where(clip.observed[..., None], clip.uv, np.nan)
    frame = most_stretched_frame(uv, skeleton)
    scaled, scale = scale_reference_frame(uv[frame], skeleton, ledger.lengths)
    ledger.add("reference_frame", scaled, lambda j: f"frame {frame}, 2D length x "
               f"{scale:.6g} {spec.units}/pixel from the known bones seen in it")

    mean_ratio, _ = bone_ratios(skeleton, ratios)
    by_ratio, finger_total = lengths_from_ratios(skeleton, ledger.lengths, mean_ratio)
    ledger.add("ratios", by_ratio, lambda j: f"X-ray ratio {mean_ratio[j]:.4f} of a "
               f"{skeleton.fingers[j]} finger of {finger_total[j]:.6g} {spec.units}")

    by_proportion, hand_length = lengths_from_hand_length(skeleton, ledger.lengths)
    ledger.add("anthropometric", by_proportion, lambda j: "Buchholz et al. 1992 proportion "
               f"of a hand length of {hand_length:.6g} {spec.units}")

    missing = [skeleton.joints[j] for j in np.flatnonzero(ledger.missing())]
    if missing:
        raise BoneLengthError(
            f"clip '{clip.clip_id}': no length for bone(s) {', '.join(missing)}: not given, "
            "not in the ground truth, not seen in the reference frame, and not a phalanx "
            f"or bone with a published proportion; add them to bone_lengths in {spec.path}")
    return BoneLengths(
        skeleton=skeleton, units=spec.units, lengths=ledger.lengths,
        sources=tuple(ledger.sources), details=tuple(ledger.details),
        residuals=ledger.residuals, n_frames=ledger.n_frames,
    )


def bone_lengths_table(clip_id: str, subject: str, skeleton: Skeleton,
                       bone_lengths: BoneLengths) -> pa.Table:
    """Build table ``bone_lengths``: one row per bone of ``skeleton``.

    Parameters
    ----------
    clip_id, subject
        The clip and its subject.
    skeleton
        The clip's skeleton (the one ``bone_lengths`` was computed for).
    bone_lengths
        The clip's lengths, from :func:`clip_bone_lengths`.
    """
    parent, child = skeleton.bones.T
    n_frames = bone_lengths.n_frames[child]
    return tables.from_columns("bone_lengths", {
        "subject": subject,
        "clip_id": clip_id,
        "bone": [skeleton.joints[c] for c in child],
        "parent": [skeleton.joints[p] for p in parent],
        "finger": [skeleton.fingers[c] for c in child],
        "length": bone_lengths.lengths[child],
        "units": bone_lengths.units,
        "source": [bone_lengths.sources[c] for c in child],
        "detail": [bone_lengths.details[c] for c in child],
        "residual": pa.array(bone_lengths.residuals[child], from_pandas=True),
        "n_frames": pa.array(n_frames, mask=n_frames == 0),
    })
