"""The length of every bone of a clip, where it came from, and how sure it is.

Depth reconstruction needs every bone's length in the clip's units. A bone's length comes
from the first of these sources that measures it:

1. ``given``: the sidecar's ``bone_lengths``, what the user measured on the subject;
2. ``truth``: the median over frames of the bone's length in the ground-truth 3D
   positions, robust to frames where a joint jumps;
3. ``calibrated``: subject calibration of a marker clip's fit
   (:func:`handdb.markers.calibration.calibrate`);

and the other bones are estimated (:mod:`handdb.lengths.estimate`), combining by their
spreads what each kind of evidence says:

4. ``clip``: the clip's own images, each bone's least-foreshortened appearances over all
   its frames, scaled by the known bones (with the X-ray and population priors below);
5. ``ratios``: a finger's phalanges from its known phalanges and the X-ray proportions of
   Chaudhry et al. (:mod:`handdb.lengths.ratios`), where the images say nothing;
6. ``proportions``: every bone a share of the hand's length (Buchholz et al. 1992 and the
   average hand's layout), the hand's length given by the known bones or by the sidecar's
   ``hand_length``;
7. ``population``: the same for an average adult hand, when the sidecar gives no length
   at all: the clip is then as large as an average hand, within the population's spread.

Every estimated length has an uncertainty (one standard deviation, clip units) in the
``bone_lengths`` table: the spreads of its evidence combined, widened by as much as the
evidence disagrees over the clip's bones beyond those spreads
(:func:`~handdb.lengths.estimate.consistency_ratio`: a held pose or a short clip gives
envelopes that disagree with the proportions), and the hand length's spread when that
alone sizes the clip (shared by every kind of evidence, it is not averaged away).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import Clip
from handdb.hand.skeletons import Skeleton, frame_bone_lengths
from handdb.lengths.estimate import (
    combine,
    consistency_ratio,
    hand_length_from,
    image_proportions,
    palm_bones,
    population_hand_length,
    proportion_lengths,
    ratio_lengths,
    sized_by_kind,
    sized_like,
)
from handdb.lengths.ratios import bone_ratios, table1_ratios
from handdb.robust import robust_spread
from handdb.store import tables

#: Every source of a bone length, most direct first.
SOURCES: tuple[str, ...] = (
    "given", "truth", "calibrated", "clip", "ratios", "proportions", "population",
)


#: Relative spread of a hand length the sidecar gives (a tape measure's).
GIVEN_HAND_LENGTH_SPREAD = 0.02


@dataclass(frozen=True)
class BoneLengths:
    """Every bone of a skeleton with its length, where that came from and its uncertainty.

    Attributes
    ----------
    skeleton
        The skeleton; arrays follow its joint order, a bone named by its child joint.
    units
        Length unit of ``lengths``, ``uncertainty`` and ``residuals``.
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
    uncertainty
        ``(J,) float64``: one standard deviation of the length, ``units``; NaN where the
        length is given.
    """

    skeleton: Skeleton
    units: str
    lengths: np.ndarray
    sources: tuple[str | None, ...]
    details: tuple[str | None, ...]
    residuals: np.ndarray
    n_frames: np.ndarray
    uncertainty: np.ndarray


def _hand_length(clip: Clip, known: np.ndarray) -> tuple[float, float, str]:
    """The clip's hand length, its relative spread, and where it came from."""
    spec = clip.spec
    if spec.hand_length is not None:
        return spec.hand_length, GIVEN_HAND_LENGTH_SPREAD, "hand_length"
    length, spread = hand_length_from(clip.skeleton, known)
    if np.isfinite(length):
        return length, spread, "known"
    length, spread = population_hand_length(spec.meters_per_unit * 1000.0)
    return length, spread, "population"


def _median_and_spread(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Median of each column of ``values`` ``(n, k)`` and the spread of that median.

    The spread is the median absolute deviation as a standard deviation, over
    ``sqrt(n)``; both are ``(k,)``, in the unit of ``values``.
    """
    return np.median(values, axis=0), robust_spread(values) / np.sqrt(len(values))


def _truth(clip: Clip) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Median length of every bone in the ground truth, its spread and its frames."""
    skeleton = clip.skeleton
    n = skeleton.n_joints
    median, spread, frames = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n, np.int64)
    if clip.truth is None:
        return median, spread, frames
    per_frame = frame_bone_lengths(clip.truth, skeleton)
    seen = np.isfinite(per_frame)
    bones = skeleton.bones[:, 1]
    complete = bones[seen[:, bones].all(axis=0)]          # in every frame: taken together
    if len(complete):
        median[complete], spread[complete] = _median_and_spread(per_frame[:, complete])
        frames[complete] = len(per_frame)
    for j in np.setdiff1d(bones, complete):
        values = per_frame[seen[:, j], j]
        if len(values):
            (median[j],), (spread[j],) = _median_and_spread(values[:, None])
            frames[j] = len(values)
    return median, spread, frames


def clip_bone_lengths(clip: Clip, ratios: pa.Table | None = None) -> BoneLengths:
    """Give every bone of a clip's skeleton a length, by the precedence of the module.

    Parameters
    ----------
    clip
        The clip: its sidecar's ``bone_lengths`` and ``hand_length``, its ``truth`` and
        its 2D tracks.
    ratios
        Table ``joint_ratios`` (cohort ``all`` is used); ``None`` or an empty table uses
        the paper's Table 1.

    Returns
    -------
    BoneLengths
        In the clip's units.

    Every bone gets a length: the average hand's layout gives one to any bone of a
    skeleton preset.
    """
    skeleton, spec = clip.skeleton, clip.spec
    if ratios is None or ratios.num_rows == 0:
        ratios = table1_ratios()
    n = skeleton.n_joints
    sidecar = Path(spec.path).name
    given = np.array([spec.bone_lengths.get(j, np.nan) for j in skeleton.joints])
    truth, truth_spread, truth_frames = _truth(clip)
    lengths = np.where(np.isfinite(given), given, truth)
    uncertainty = np.where(np.isfinite(given), np.nan, truth_spread)
    sources: list[str | None] = [None] * n
    details: list[str | None] = [None] * n
    for j in skeleton.bones[:, 1]:
        if np.isfinite(given[j]):
            sources[j], details[j] = "given", f"bone_lengths in {sidecar}"
        elif np.isfinite(truth[j]):
            sources[j] = "truth"
            details[j] = f"median over {truth_frames[j]} frames of the ground truth"

    hand_length, hand_spread, hand_origin = _hand_length(clip, lengths)
    # Known bones size the images, and the proportions by a hand length of their own
    # errors; without one, the hand length sizes every kind of evidence alike, so its
    # spread is shared and joins after they are combined, not once per kind.
    sized = bool(np.isfinite(lengths).any())
    own_spread, shared_spread = (hand_spread, 0.0) if sized else (0.0, hand_spread)
    proportions = proportion_lengths(skeleton, hand_length, own_spread)
    uv = np.where(clip.observed[..., None], clip.uv, np.nan)
    shape = image_proportions(uv, skeleton, proportions.lengths)
    if sized:
        images = sized_by_kind(shape, lengths, palm_bones(skeleton))
    else:
        images = sized_like(shape, proportions)
    mean_ratio, _ = bone_ratios(skeleton, ratios)
    phalanges = ratio_lengths(skeleton, np.where(np.isfinite(lengths), lengths,
                                                 images.lengths), mean_ratio)
    evidence = [images, proportions, phalanges]
    estimate = combine(evidence)
    estimated = np.array([j for j in skeleton.bones[:, 1] if sources[j] is None], dtype=int)
    widening = consistency_ratio(evidence, estimate, estimated)
    spread = np.hypot(widening * estimate.spread, shared_spread)
    for j in skeleton.bones[:, 1]:
        if sources[j] is not None or not np.isfinite(estimate.lengths[j]):
            continue
        lengths[j] = estimate.lengths[j]
        uncertainty[j] = spread[j] * estimate.lengths[j]
        if np.isfinite(images.lengths[j]):
            sources[j] = "clip"
            details[j] = (f"upper envelope over {images.n_frames[j]} frames of its image "
                          "length, scaled by the known bones, with the X-ray and hand "
                          "proportions as priors")
        elif np.isfinite(phalanges.lengths[j]):
            sources[j] = "ratios"
            details[j] = ("X-ray share of its finger's other phalanges, with the hand's "
                          "proportions")
        else:
            sources[j] = "population" if hand_origin == "population" else "proportions"
            details[j] = {
                "hand_length": f"its share of the hand_length in {sidecar}",
                "known": f"its share of a {hand_length:.4g} {spec.units} hand, from the "
                         "known bones",
                "population": f"its share of an average adult hand ({hand_length:.4g} "
                              f"{spec.units}): {sidecar} gives no length",
            }[hand_origin]
    n_frames = np.where(np.array([s == "truth" for s in sources]), truth_frames,
                        np.where(np.array([s == "clip" for s in sources]), images.n_frames, 0))
    return BoneLengths(skeleton=skeleton, units=spec.units, lengths=lengths,
                       sources=tuple(sources), details=tuple(details),
                       residuals=np.full(n, np.nan), n_frames=n_frames.astype(np.int64),
                       uncertainty=uncertainty)


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
        "uncertainty": pa.array(bone_lengths.uncertainty[child], from_pandas=True),
        "residual": pa.array(bone_lengths.residuals[child], from_pandas=True),
        "n_frames": pa.array(n_frames, mask=n_frames == 0),
    })
