"""Bone lengths a clip does not give, estimated from the whole clip and from hands in general.

Three kinds of evidence meet here, each with its spread, and are combined per bone by
inverse variance in log length (lengths are positive and their errors relative):

* **the clip's images**: a bone of length ``l`` spans ``p_t = s_t l |cos theta_t|`` pixels in
  frame ``t`` (scaled orthography; a pinhole camera at the hand's distance alike), so
  ``p_t / s_t <= l`` with equality whenever the bone lies in the image plane. Over many
  frames the upper envelope of ``p_t / s_t``, its least-foreshortened appearances, is the
  bone's length (:func:`envelope_lengths`). The frame's scale ``s_t`` is the thesis's eq. 6
  bound over all the hand's bones (:func:`clip_scale`), tight whenever some bone lies in
  the image plane, which in most frames one does: scale and lengths are found together
  (:func:`image_proportions`), up to a factor, which the known bones fix: the palm's
  bones from the wrist by the known ones among them, the others by theirs
  (:func:`sized_by_kind`). One frame assumed flat, the thesis's reference frame
  (:func:`reference_frame_lengths`), is the baseline this replaces.
* **X-ray proportions** (Chaudhry et al.): a finger's phalanges in the shares the X-ray
  hands show, from the phalanges of that finger that are known.
* **anthropometric proportions** (Buchholz et al. 1992, and the mean palm's layout): every
  bone a share of the hand's length, which the known bones (or the sidecar's
  ``hand_length``, or, lacking both, the adult population) give.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from handdb.compiled import kernel
from handdb.hand.anatomy import MEAN_HAND_LENGTH_MM
from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import Skeleton, frame_bone_lengths, load_skeleton
from handdb.lifting.geometry import eq6_scale
from handdb.lifting.temporal import smooth_scale

#: The scale of a frame is this upper percentile of the eq. 6 bounds over a window of
#: :data:`SCALE_HALF_WINDOW` frames each side: the bound is tight only in frames where some
#: bone lies in the image plane.
SCALE_PERCENTILE = 75.0
SCALE_HALF_WINDOW = 30

#: With this many bones or more, a frame's bound is the second-largest ratio of image to
#: bone length (one jittering bone cannot set it), else the largest (eq. 6).
ROBUST_SCALE_BONES = 4

#: Rounds of scale from lengths and lengths from scale in :func:`image_proportions`.
PROPORTION_ROUNDS = 3

#: A bone's image length is its length's upper envelope at this percentile over the
#: frames (not the maximum: trackers jump).
ENVELOPE_PERCENTILE = 95.0

#: Each bone's image length is a running median over this many frames before its envelope
#: is taken: trackers jitter from frame to frame, and the upper envelope of a jittering
#: length is the jitter's, not the bone's.
JITTER_FRAMES = 5

#: Frames a bone must be seen in for its envelope to count.
MIN_ENVELOPE_FRAMES = 20

#: Relative spread of an envelope: the floor (pixel noise, scale error), and how much the
#: gap between the envelope's upper percentiles adds (a bone seldom in the image plane has
#: a loose envelope).
ENVELOPE_SPREAD_FLOOR = 0.04
ENVELOPE_GAP_PERCENTILES = (80.0, 99.0)

#: Roles of the joints that end the palm's bones from the wrist (to a long finger's knuckle
#: or a palm centre), sized by the known ones among them (:func:`sized_by_kind`).
PALM_ROLES = frozenset({"mcp", "palm_center", "palm_fold"})

#: Relative spread of a phalanx about its X-ray share of the finger's known phalanges.
RATIO_SPREAD = 0.08

#: Relative spread of a bone about its Buchholz proportion of the hand's length: adult
#: proportions vary by a few percent; a bone from the wrist by more, as datasets put the
#: wrist point in different places.
PROPORTION_SPREAD = 0.08
WRIST_PROPORTION_SPREAD = 0.2

#: Relative spread of adult hand length about the average (men about 190 mm, women 173).
POPULATION_SPREAD = 0.06


@dataclass(frozen=True)
class Estimate:
    """Lengths with their spreads, one per bone.

    Attributes
    ----------
    lengths
        ``(J,) float64``, clip units; NaN where this evidence says nothing.
    spread
        ``(J,) float64``: relative standard deviation of each length (of its logarithm).
    n_frames
        ``(J,) int64``: frames the evidence comes from, 0 where none.
    """

    lengths: np.ndarray
    spread: np.ndarray
    n_frames: np.ndarray


def clip_scale(projected: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Each frame's image scale from bone lengths.

    Parameters
    ----------
    projected
        ``(T, J) float64`` image length of the bone ending at each joint, pixels
        (:func:`~handdb.hand.skeletons.frame_bone_lengths` of the 2D points); NaN where
        an end is missing.
    lengths
        ``(J,) float64`` bone lengths, clip units; NaN where unknown.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``, pixels per clip unit; NaN when no bone of known length is ever
        seen. With :data:`ROBUST_SCALE_BONES` lengths or more, one bone may jitter.
    """
    rank = 2 if np.isfinite(lengths).sum() >= ROBUST_SCALE_BONES else 1
    bounds = eq6_scale(projected, lengths, rank=rank)
    return smooth_scale(bounds, percentile=SCALE_PERCENTILE, half_window=SCALE_HALF_WINDOW)


def running_median(values: np.ndarray, frames: int) -> np.ndarray:
    """Median of each column over ``frames`` consecutive rows centred on each row.

    ``values`` is ``(T, N)``; NaNs are ignored, and a row stays NaN where it was or where
    fewer than half its window is finite. The ends use the windows that fit.

    Each window's ``n`` finite values are sorted and its median read off them as the
    mean of ranks ``(n - 1) // 2`` and ``n // 2``, as :func:`numpy.nanmedian` gives it,
    without that function's cost per window.
    """
    if frames <= 1 or len(values) < frames:
        return values.copy()
    median = np.empty(values.shape)
    _running_median(np.ascontiguousarray(values, dtype=np.float64), frames, median)
    return median


@kernel
def _running_median(values, frames, median):
    """Fill ``median`` ``(T, N)`` with :func:`running_median` of ``values`` ``(T, N)``."""
    n_frames, n_columns = values.shape
    half = frames // 2
    window = np.empty(frames)
    for column in range(n_columns):
        for t in range(n_frames):
            median[t, column] = np.nan
            if not np.isfinite(values[t, column]):
                continue
            n = 0
            for s in range(max(0, t - half), min(n_frames, t + half + 1)):
                value = values[s, column]
                if np.isfinite(value):
                    k = n                               # insertion sort, ascending
                    while k > 0 and window[k - 1] > value:
                        window[k] = window[k - 1]
                        k -= 1
                    window[k] = value
                    n += 1
            if 2 * n >= frames:
                median[t, column] = (window[(n - 1) // 2] + window[n // 2]) / 2


def envelope_lengths(projected: np.ndarray, scale: np.ndarray) -> Estimate:
    """Every bone's length from its least-foreshortened appearances.

    Parameters
    ----------
    projected
        ``(T, J) float64`` image bone lengths, pixels, as for :func:`clip_scale`.
    scale
        ``(T,) float64``, pixels per clip unit (:func:`clip_scale`).

    Returns
    -------
    Estimate
        Lengths of the bones seen in at least :data:`MIN_ENVELOPE_FRAMES` frames.
    """
    ratio = running_median(projected / scale[:, None], JITTER_FRAMES)
    n = projected.shape[1]
    lengths, spread = np.full(n, np.nan), np.full(n, np.nan)
    finite = np.isfinite(ratio)
    seen = finite.sum(axis=0)
    # each bone's seen values first, ascending (NaN sorts last): the bones seen in as many
    # frames share one percentile call, which takes the same order statistics as one
    # call per bone on its seen values
    ordered = np.sort(np.where(finite, ratio, np.nan), axis=0)
    bones = np.flatnonzero(seen >= MIN_ENVELOPE_FRAMES)
    for count in np.unique(seen[bones]):
        group = bones[seen[bones] == count]
        low, high, lengths[group] = np.percentile(
            ordered[:count, group], [*ENVELOPE_GAP_PERCENTILES, ENVELOPE_PERCENTILE], axis=0)
        spread[group] = ENVELOPE_SPREAD_FLOOR + (high - low) / lengths[group] / 2.0
    return Estimate(lengths, spread, np.where(np.isfinite(lengths), seen, 0))


def image_proportions(uv: np.ndarray, skeleton: Skeleton, prior: np.ndarray) -> Estimate:
    """The bones' lengths the images show, up to one factor for the whole clip.

    Scale per frame from the lengths (:func:`clip_scale`) and lengths from the scale
    (:func:`envelope_lengths`), :data:`PROPORTION_ROUNDS` times, starting from ``prior``.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels; NaN where missing.
    skeleton
        The skeleton of the joint axis.
    prior
        ``(J,) float64``: a first guess at the lengths in any unit (say the average
        hand's proportions); only their ratios matter.

    Returns
    -------
    Estimate
        Lengths in the unit of ``prior`` roughly, to be sized by :func:`sized_like`.
    """
    projected = frame_bone_lengths(uv, skeleton)
    lengths = prior
    for _ in range(PROPORTION_ROUNDS):
        images = envelope_lengths(projected, clip_scale(projected, lengths))
        if not np.isfinite(images.lengths).any():
            return images
        lengths = images.lengths
    return images


def sized_like(shape: Estimate, size: Estimate, size_spread: float = 0.0) -> Estimate:
    """The lengths of ``shape``, scaled as a whole to agree with ``size``.

    The factor is the inverse-variance mean, in log length, of ``size / shape`` over the
    bones both give; its spread, and ``size_spread`` (a spread all of ``size``'s lengths
    share, such as a hand length's), add to every length's own.

    Parameters
    ----------
    shape
        Lengths up to a factor (:func:`image_proportions`).
    size
        Lengths in clip units: the known bones (spread 0), or bones as shares of a hand
        length (their spreads about their shares).
    size_spread
        Relative spread common to all of ``size``.

    Returns
    -------
    Estimate
        ``shape`` in clip units; all NaN when no bone is in both.
    """
    both = np.isfinite(shape.lengths) & np.isfinite(size.lengths)
    if not both.any():
        return Estimate(np.full_like(shape.lengths, np.nan), np.full_like(shape.spread, np.nan),
                        np.zeros_like(shape.n_frames))
    weights = 1.0 / (shape.spread[both] ** 2 + size.spread[both] ** 2)
    factor = np.exp(np.sum(weights * np.log(size.lengths[both] / shape.lengths[both]))
                    / weights.sum())
    factor_spread = np.sqrt(1.0 / weights.sum() + size_spread ** 2)
    return Estimate(shape.lengths * factor, np.hypot(shape.spread, factor_spread),
                    shape.n_frames)


def palm_bones(skeleton: Skeleton) -> np.ndarray:
    """Which bones are the palm's from the wrist, ``(J,) bool`` by child joint.

    The bones from the root to the long fingers' knuckles (and to a palm centre): they
    share the wrist point, wherever an annotation puts it, and turn with the palm.
    """
    return np.array([p == skeleton.root and skeleton.fingers[j] != "thumb"
                     and skeleton.roles[j] in PALM_ROLES
                     for j, p in enumerate(skeleton.parents)])


def sized_by_kind(shape: Estimate, known: np.ndarray, kind: np.ndarray) -> Estimate:
    """The lengths of ``shape``, each of two kinds of bone sized by its own known bones.

    One factor for the whole clip (:func:`sized_like`) is right only if every bone's
    envelope falls short of its length by the same share; the palm's bones from the wrist
    turn with the palm as a whole and seldom lie as flat in the image as the phalanges, so
    theirs falls short by more (3-5 % on hands of the synthetic population sized by the
    middle finger's bones and the thumb base). A kind with a known bone seen is sized by
    its own known bones; a kind without, by all of them.

    Parameters
    ----------
    shape
        Lengths up to a factor (:func:`image_proportions`).
    known
        ``(J,) float64`` known lengths, clip units; NaN where unknown.
    kind
        ``(J,) bool``: the bones of one kind (:func:`palm_bones`); the rest are the other.

    Returns
    -------
    Estimate
        ``shape`` in clip units.
    """
    zero = np.zeros_like(known)
    everyone = sized_like(shape, Estimate(known, zero, shape.n_frames))
    lengths, spread = everyone.lengths.copy(), everyone.spread.copy()
    for bones in (kind, ~kind):
        if not np.isfinite(known[bones] * shape.lengths[bones]).any():
            continue
        own = sized_like(Estimate(np.where(bones, shape.lengths, np.nan), shape.spread,
                                  shape.n_frames),
                         Estimate(np.where(bones, known, np.nan), zero, shape.n_frames))
        lengths[bones], spread[bones] = own.lengths[bones], own.spread[bones]
    return Estimate(lengths, spread, shape.n_frames)


def ratio_lengths(skeleton: Skeleton, known: np.ndarray, mean_ratio: np.ndarray) -> Estimate:
    """Phalanges from the other known phalanges of their finger and the X-ray ratios.

    Each known phalanx ``k`` of a finger gives the finger's total as ``known_k /
    ratio_k``; for every phalanx, the mean over the finger's other known phalanges times
    its own ratio is its length (a known phalanx is not its own evidence).

    Parameters
    ----------
    skeleton
        The skeleton of the joint axis.
    known
        ``(J,) float64`` known lengths; NaN where unknown.
    mean_ratio
        ``(J,) float64`` mean relative length of each phalanx in its finger
        (:func:`handdb.lengths.ratios.bone_ratios`); NaN for other bones.
    """
    fingers = np.array(skeleton.fingers)
    anchors = np.isfinite(known) & np.isfinite(mean_ratio)
    votes = ((fingers[:, None] == fingers[None, :]) & anchors[None, :]
             & ~np.eye(skeleton.n_joints, dtype=bool))
    estimates = np.where(anchors, known / np.where(anchors, mean_ratio, 1.0), 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        total = (votes @ estimates) / votes.sum(axis=1)
    lengths = total * mean_ratio
    return Estimate(lengths, np.where(np.isfinite(lengths), RATIO_SPREAD, np.nan),
                    np.zeros(skeleton.n_joints, dtype=np.int64))


@cache
def _hand_proportions(skeleton_name: str) -> np.ndarray:
    shape = mean_shape()
    proportions = shape.bone_lengths(load_skeleton(skeleton_name)) / shape.hand_length
    proportions.flags.writeable = False
    return proportions


def hand_proportions(skeleton: Skeleton) -> np.ndarray:
    """Each bone's share of the hand's length in the average hand, ``(J,)``; NaN at the root.

    The average hand (:func:`handdb.hand.shape.mean_shape`) follows Buchholz et al. for
    the metacarpals and phalanges and the mean palm's layout for the rest (the thumb
    base, the palm centre and fold).
    """
    return _hand_proportions(skeleton.name).copy()


def proportion_spread(skeleton: Skeleton) -> np.ndarray:
    """Relative spread of each bone about its share of the hand's length, ``(J,)``."""
    from_wrist = np.array([p >= 0 and skeleton.roles[p] == "wrist" for p in skeleton.parents])
    return np.where(from_wrist, WRIST_PROPORTION_SPREAD, PROPORTION_SPREAD)


def hand_length_from(skeleton: Skeleton, known: np.ndarray) -> tuple[float, float]:
    """The hand's length the known bones imply, and its relative spread.

    Each known bone gives ``length / share`` (:func:`hand_proportions`); they are
    combined by inverse variance. ``(nan, nan)`` when no bone is known.
    """
    proportion = hand_proportions(skeleton)
    anchors = np.isfinite(known) & np.isfinite(proportion)
    if not anchors.any():
        return np.nan, np.nan
    logs = np.log(known[anchors] / proportion[anchors])
    weights = 1.0 / proportion_spread(skeleton)[anchors] ** 2
    return float(np.exp(np.sum(weights * logs) / weights.sum())), float(
        1.0 / np.sqrt(weights.sum()))


def proportion_lengths(skeleton: Skeleton, hand_length: float,
                       hand_spread: float = 0.0) -> Estimate:
    """Every bone as its share of a hand of ``hand_length``.

    Each length's spread is its share's (:func:`proportion_spread`) and ``hand_spread``,
    the hand length's relative spread, in quadrature.
    """
    lengths = hand_proportions(skeleton) * hand_length
    spread = np.sqrt(proportion_spread(skeleton) ** 2 + hand_spread ** 2)
    return Estimate(lengths, np.where(np.isfinite(lengths), spread, np.nan),
                    np.zeros(skeleton.n_joints, dtype=np.int64))


def population_hand_length(mm_per_unit: float) -> tuple[float, float]:
    """The average adult hand's length in clip units, and its relative spread."""
    return MEAN_HAND_LENGTH_MM / mm_per_unit, POPULATION_SPREAD


def combine(estimates: list[Estimate]) -> Estimate:
    """Inverse-variance combination in log length of several estimates, bone by bone.

    A bone none of them gives stays NaN.
    """
    logs = np.stack([np.log(e.lengths) for e in estimates])
    weights = np.stack([1.0 / e.spread ** 2 for e in estimates])
    given = np.isfinite(logs) & np.isfinite(weights)
    weights = np.where(given, weights, 0.0)
    total = weights.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.sum(np.where(given, logs, 0.0) * weights, axis=0) / total
        spread = 1.0 / np.sqrt(total)
    frames = np.stack([e.n_frames for e in estimates]).max(axis=0)
    found = total > 0
    return Estimate(np.where(found, np.exp(mean), np.nan), np.where(found, spread, np.nan),
                    np.where(found, frames, 0))


def consistency_ratio(estimates: list[Estimate], combined: Estimate, bones: np.ndarray
                      ) -> float:
    """How much more the estimates disagree than their spreads allow, over a clip's bones.

    The Birge ratio: ``sqrt(chi2 / dof)`` of the estimates about their combination
    (:func:`combine`), pooled over ``bones``, in log length; each bone given by ``n``
    estimates adds ``n - 1`` degrees of freedom. Evidence that agrees within its spreads
    gives about 1; evidence that says more than it knows (an envelope from a held pose or a
    short clip, proportions of an annotation that puts its joints elsewhere) gives more,
    and each combined spread is too small by about that factor.

    Parameters
    ----------
    estimates
        The evidence :func:`combine` combined.
    combined
        Their combination.
    bones
        ``(B,) int``: the bones (by child joint) to pool over, the ones being estimated.

    Returns
    -------
    float
        At least 1 (evidence that agrees better than its spreads does not make them
        smaller); 1 when no bone has two estimates.
    """
    logs = np.stack([np.log(e.lengths[bones]) for e in estimates])
    spreads = np.stack([e.spread[bones] for e in estimates])
    given = np.isfinite(logs) & np.isfinite(spreads)
    z = np.where(given, (logs - np.log(combined.lengths[bones])) / np.where(given, spreads, 1.0),
                 0.0)
    dof = np.maximum(given.sum(axis=0) - 1, 0).sum()
    if dof == 0:
        return 1.0
    return max(1.0, float(np.sqrt(np.sum(z ** 2) / dof)))


def reference_frame_lengths(uv: np.ndarray, skeleton: Skeleton, known: np.ndarray
                            ) -> np.ndarray:
    """The thesis's reference hand (Nopvichai 2009, §3.2), the baseline of this module.

    In the frame where the hand is most stretched in 2D (the most bones seen, the longest
    in total), taken to be flat and facing the camera, 2D lengths are proportional to 3D
    lengths; the known bones seen in it give the scale.

    Returns
    -------
    numpy.ndarray
        ``(J,) float64``, clip units: every bone seen in that frame; NaN elsewhere, and
        everywhere when no known bone is seen in it.
    """
    pixels = frame_bone_lengths(uv, skeleton)
    seen = np.isfinite(pixels).sum(axis=1)
    frame = int(np.argmax(np.where(seen == seen.max(), np.nansum(pixels, axis=1), -np.inf)))
    anchors = np.isfinite(known) & (pixels[frame] > 0)
    if not anchors.any():
        return np.full(skeleton.n_joints, np.nan)
    return pixels[frame] * float(np.median(known[anchors] / pixels[frame][anchors]))
