"""``auto``, the default: per gap, the method that suits it, in the palm frame, then refined.

0. Detector jitter is measured and, where a smoothing window lowers Stein's risk, the
   observed tracks are smoothed (:mod:`handdb.denoise`); everything below reads
   the smoothed tracks, and the observed points are returned as they were.
1. The palm's affine motion is fitted frame by frame and every track is expressed in the
   palm frame (:mod:`handdb.gapfill.palm_frame`), where only finger bending is left to
   bridge.
2. Palm points (wrist, finger bases) stand still there: every gap of theirs is bridged by
   interpolation and held at the clip's ends, which makes a rigid-body fill; a second
   rigid-body fill carries the point from its gap's edges with the palm points seen there
   (:func:`palm_gap_fill`), and the two are weighed per joint by validation, as in 4.
3. Finger points in interior gaps of at most ``short_gap`` frames: PCHIP interpolation;
   so are, in the image, all the points of a frame that observes none.
4. Finger points in longer, leading or trailing gaps: two estimates from the other joints,
   the point carried with its parent bone (:func:`~handdb.gapfill.rigid.carry_along_chains`,
   the joint's angle changing linearly across the gap) and a ridge regression on the finger
   joints seen throughout the gap (:mod:`handdb.gapfill.regression`; a joint's dropouts no
   longer than the smoothing's half-width are read as interpolated, so a detector's
   dropout of a frame or two does not remove a predictor), are weighed per joint
   by how well each refills runs of that joint's own observed frames hidden on purpose
   (:func:`validation_mask` and, beside a leading or trailing gap,
   :func:`edge_validation_mask`, which hides the frames next to the gap so that the trial
   extrapolates as far as the gap does, across short dropouts): weights inversely
   proportional to the squared validation error. ``long_gaps`` picks one estimate instead
   (``"chain"``, ``"regression"``, or ``"lowrank"``, the iterated PCA of
   :mod:`handdb.gapfill.lowrank`).
5. Joints never observed are placed first, so that the other joints can lean on them:
   between their parent and only child where both are observed (a DIP an annotation
   skips, :func:`~handdb.gapfill.rigid.place_on_chords`, label ``chord``), else by the
   rest pose fitted to the observed joints of each frame, and bridged like any gap across
   frames that observe too little to fit it to. A clip no frame of which observes enough
   of the palm is refused (:func:`check_placeable`).
6. Kinematic refinement (:mod:`handdb.gapfill.refine`): filled points are pulled back
   where they would stretch a bone beyond its length.

Frames that observe no point are filled like any gap in interior runs of at most
``short_gap`` frames; runs at the clip's ends, or longer, stay unfilled (NaN) and split the
clip into segments filled on their own (:func:`track_segments`).

Each filled point is labelled with the rule that filled it (``rigid``, ``pchip``,
``validated``, ``chord``, ``rest-pose``).

The validation's hidden runs and the real gaps are estimated together: one set of
regression samples, their regressions in shared batches, their chain fills by one compiled
kernel each. Only the filled points are mapped back to the image.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from handdb.clip import finite_points
from handdb.compiled import kernel
from handdb.denoise import denoise
from handdb.errors import GapFillError, ParameterError
from handdb.gapfill.gaps import Gaps, find_gaps, mask_points
from handdb.gapfill.interpolate import interpolate_gaps
from handdb.gapfill.lowrank import DEFAULT_VARIANCE, blend_to_edges, lowrank_reconstruct
from handdb.gapfill.palm_frame import palm_motion, to_image, to_palm_frame
from handdb.gapfill.refine import refine_bone_lengths
from handdb.gapfill.registry import MethodOutput
from handdb.gapfill.regression import regression_estimates, regression_samples
from handdb.gapfill.rigid import (
    MIN_PALM_POINTS,
    carried_points,
    carry_along_chains_many,
    palm_joints,
    place_from_rest_pose,
    place_on_chords,
    placeable_frames,
)
from handdb.hand.skeletons import Skeleton

#: Longest interior gap (frames) bridged by interpolation rather than by the other joints.
SHORT_GAP = 8

#: Ways of filling long finger gaps from the other joints (see :func:`estimate_long_gaps`).
ESTIMATES = ("chain", "regression", "lowrank")
#: How long finger gaps are filled: one estimate, or several weighed by validation.
LONG_GAP_RULES = (*ESTIMATES, "validated")
#: The estimates weighed by ``"validated"``.
VALIDATED_ESTIMATES = ("chain", "regression")

#: The labels of the points the hand model places: joints never observed.
MODEL_RULES = ("chord", "rest-pose")
#: The labels of the points ``auto`` fills, by the rule that filled them.
RULE_LABELS = ("rigid", "pchip", *LONG_GAP_RULES, *MODEL_RULES)

#: Observed runs per joint hidden to weigh the long-gap estimates against each other.
VALIDATION_GAPS = 3


def estimate_long_gaps(
    estimates: tuple[str, ...], local: np.ndarray, filled: np.ndarray,
    problems: Sequence[tuple[np.ndarray, Gaps]], skeleton: Skeleton,
    variance: float = DEFAULT_VARIANCE, reach: int = 1, bridged: int = 0,
) -> list[list[np.ndarray]]:
    """Estimate the points of long finger gaps by each of ``estimates``.

    Parameters
    ----------
    estimates
        Names from :data:`ESTIMATES`: ``"chain"``
        (:func:`~handdb.gapfill.rigid.carry_along_chains`), ``"regression"``
        (:func:`~handdb.gapfill.regression.regression_estimates` on the finger joints, the
        chain where it cannot) and ``"lowrank"`` (:mod:`handdb.gapfill.lowrank`).
    local
        ``(T, J, 2)`` tracks in the palm frame (read by ``"lowrank"`` where observed).
    filled
        ``local`` with the palm points and every gap filled by interpolation.
    problems
        ``(missing, gaps)`` pairs: ``(T, J) bool`` points taken as missing (those of the
        clip, and maybe observed ones hidden on purpose) and the gaps to estimate. The
        problems' regressions are solved together.
    skeleton, variance
        The skeleton, the low-rank variance share.
    reach
        Observed frames at each edge of a gap that ``"chain"`` carries the point from
        (:func:`~handdb.gapfill.rigid.carry_along_chains_many`), at least 1.
    bridged
        Longest interior gap, frames, across which ``"regression"`` reads a joint from
        ``filled`` as if observed (:func:`_unbridged`): a predictor seen throughout a gap
        but for a dropout of a frame or two still predicts, and those frames train.

    Returns
    -------
    list of list of numpy.ndarray
        Per problem, per estimate, ``(N, 2) float64``: the estimates at the points of
        ``gaps.frames()``, in order.
    """
    points = [gaps.frames()[1:] for _, gaps in problems]
    chains = [carried[frame, joint] for carried, (frame, joint) in zip(
        carry_along_chains_many(filled, problems, skeleton,
                                [np.full(len(gaps), reach) for _, gaps in problems]),
        points, strict=True)]
    results: list[dict[str, np.ndarray]] = [{"chain": chain} for chain in chains]
    if "regression" in estimates:
        fingers = ~palm_joints(skeleton)
        read = [(_unbridged(missing, gaps, bridged), gaps) for missing, gaps in problems]
        missing_in_all = np.logical_and.reduce([missing for missing, _ in read])
        samples = regression_samples(filled, missing_in_all, np.flatnonzero(fingers))
        regressed = regression_estimates(samples, fingers, read)
        for result, chain, estimate in zip(results, chains, regressed, strict=True):
            result["regression"] = np.where(np.isnan(estimate), chain, estimate)
    if "lowrank" in estimates:
        for result, (missing, gaps), (frame, joint) in zip(results, problems, points,
                                                           strict=True):
            model = lowrank_reconstruct(local, missing, variance=variance)
            result["lowrank"] = blend_to_edges(filled, model, gaps)[frame, joint]
    return [[result[name] for name in estimates] for result in results]


def _unbridged(missing: np.ndarray, gaps: Gaps, bridged: int) -> np.ndarray:
    """``missing`` without the points of its interior gaps of at most ``bridged`` frames.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    gaps
        The gaps to estimate (of ``missing``): their points stay missing.
    bridged
        Longest interior gap taken as observed, frames; 0 for none.

    Returns
    -------
    numpy.ndarray
        ``(T, J) bool``: ``missing`` itself when nothing is bridged, else a copy.
    """
    if bridged <= 0:
        return missing
    every = find_gaps(missing)
    short = every.select(every.interior & (every.length <= bridged))
    if not len(short):
        return missing
    unbridged = missing.copy()
    _, frame, joint = short.frames()
    unbridged[frame, joint] = False
    _, frame, joint = gaps.frames()
    unbridged[frame, joint] = True
    return unbridged


def validation_mask(missing: np.ndarray, gaps: Gaps, seed: int = 0) -> np.ndarray:
    """Hide observed runs of the joints of ``gaps``, as long as their gaps, to score rules.

    For each joint, up to :data:`VALIDATION_GAPS` runs of the median length of its gaps are
    placed at random where the joint is observed throughout the run and one frame
    either side.

    Returns
    -------
    numpy.ndarray
        ``(T, J) bool``: the points to hide (never a missing point).
    """
    rng = np.random.default_rng(seed)
    n_frames = missing.shape[0]
    by_joint = np.lexsort((gaps.length, gaps.joint))
    joints, first, counts = np.unique(gaps.joint[by_joint], return_index=True,
                                      return_counts=True)
    ordered = gaps.length[by_joint]
    medians = 0.5 * (ordered[first + (counts - 1) // 2] + ordered[first + counts // 2])
    lengths = np.minimum(medians, n_frames // 4).astype(np.int64)
    starts, n_starts = _clear_starts(missing, joints, lengths)
    picks = [rng.permutation(n)[:VALIDATION_GAPS] for n in n_starts]
    owner = np.repeat(np.arange(joints.size), [pick.size for pick in picks])
    first_start = np.cumsum(n_starts) - n_starts
    chosen = starts[first_start[owner] + np.concatenate([np.empty(0, dtype=np.int64), *picks])]
    hidden = np.zeros_like(missing)
    _hide_runs(hidden, joints[owner], lengths[owner], chosen)
    return hidden


@kernel
def _clear_starts(
    missing: np.ndarray, joints: np.ndarray, lengths: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The frames where a run of each joint can start, observed one frame either side.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    joints, lengths
        ``(K,) int64``: the joints, and the length of their runs, frames.

    Returns
    -------
    starts
        ``(S,) int64``: each joint's possible first frames (from 1), ascending, joint after
        joint, where the joint is observed from the frame before to the frame after the run.
    n_starts
        ``(K,) int64``: how many of ``starts`` are each joint's.
    """
    n_frames = missing.shape[0]
    starts = np.empty(joints.size * n_frames, dtype=np.int64)
    n_starts = np.zeros(joints.size, dtype=np.int64)
    missing_so_far = np.zeros(n_frames + 1, dtype=np.int64)
    total = 0
    for index in range(joints.size):
        joint, length = joints[index], lengths[index]
        for frame in range(n_frames):
            missing_so_far[frame + 1] = missing_so_far[frame] + missing[frame, joint]
        for start in range(1, n_frames - length):
            if missing_so_far[start + length + 1] == missing_so_far[start - 1]:
                starts[total] = start
                total += 1
                n_starts[index] += 1
    return starts[:total], n_starts


@kernel
def _hide_runs(hidden: np.ndarray, joint: np.ndarray, length: np.ndarray, start: np.ndarray
               ) -> None:
    """Hide runs in turn, each unless it would touch a run hidden before.

    Parameters
    ----------
    hidden
        ``(T, J) bool``, modified.
    joint, length, start
        ``(R,) int64``: each run's joint, length (frames) and first frame (from 1, ending
        before the last frame).
    """
    for run in range(joint.size):
        first, stop, j = start[run], start[run] + length[run], joint[run]
        if not hidden[first - 1:stop + 1, j].any():
            hidden[first:stop, j] = True


def edge_validation_mask(missing: np.ndarray, gaps: Gaps, bridged: int = 0) -> np.ndarray:
    """Hide, beside each leading or trailing gap, the observed frames next to it.

    A trailing gap of ``L`` frames is extrapolated ``L`` frames past the joint's last
    observed frame; hiding the ``L`` observed frames before it (all but the first of their
    run) makes a trial that extrapolates as far, from an earlier frame, with the truth
    known. Likewise after a leading gap (all but the last of the run). A run between a
    leading and a trailing gap is split at its middle frame, which stays observed, each
    trial hiding frames on its own side only. Whole-clip gaps get no run.

    Interior gaps of at most ``bridged`` frames (a detector's short dropouts, which the
    fill bridges by interpolation) do not end the run: the trial hides the observed frames
    on both sides of them, and so extrapolates as far as the real gap does. Were the run
    cut at the dropout, a dropout just before a 48-frame trailing gap would leave a trial
    of a few frames, which weighs the estimates by how they extrapolate a few frames.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    gaps
        The gaps to be filled (of ``missing``).
    bridged
        Longest interior gap, frames, that a trial's run reaches across.

    Returns
    -------
    numpy.ndarray
        ``(T, J) bool``: the points to hide (never a missing point).
    """
    hidden = np.zeros_like(missing)
    edges = gaps.select((gaps.leading | gaps.trailing) & ~gaps.whole_clip)
    if not len(edges):
        return hidden
    n_frames = missing.shape[0]
    everything = find_gaps(missing)
    for joint, start, stop, leading in zip(edges.joint, edges.start, edges.stop,
                                           edges.leading, strict=True):
        own = everything.select((everything.joint == joint)
                                & ~(everything.interior & (everything.length <= bridged)))
        length = stop - start
        if leading:
            later = own.start > stop
            end = int(own.start[later][0]) if later.any() else n_frames
            # A run between a leading and a trailing gap is shared: each trial keeps to its
            # half, the middle frame observed.
            shared = later.any() and own.stop[later][0] == n_frames
            last = stop + (end - stop) // 2 if shared else end - 1
            hidden[stop:min(stop + length, last), joint] = True
        else:
            earlier = own.stop < start
            first = int(own.stop[earlier][-1]) if earlier.any() else 0
            shared = earlier.any() and own.start[earlier][-1] == 0
            kept = first + (start - first) // 2 if shared else first
            hidden[max(start - length, kept + 1):start, joint] = True
    return hidden & ~missing


def validation_trials(missing: np.ndarray, gaps: Gaps, bridged: int = 0
                      ) -> tuple[np.ndarray, np.ndarray, Gaps]:
    """The trials that weigh estimates of ``gaps``: observed runs hidden on purpose.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    gaps
        The gaps to be filled (of ``missing``).
    bridged
        Longest interior gap, frames, that an edge trial reaches across
        (:func:`edge_validation_mask`).

    Returns
    -------
    hidden
        ``(T, J) bool``: the observed points hidden (:func:`validation_mask` and
        :func:`edge_validation_mask`).
    trial_missing
        ``missing | hidden``.
    trial_gaps
        The gaps of ``trial_missing`` holding a hidden point (a hidden run, or one merged
        with the real gap beside it), to be scored on their hidden points only.
    """
    hidden = validation_mask(missing, gaps) | edge_validation_mask(missing, gaps, bridged)
    trial_missing = missing | hidden
    trial_gaps = find_gaps(trial_missing)
    hidden_so_far = np.concatenate([np.zeros((1, missing.shape[1]), dtype=np.int64),
                                    np.cumsum(hidden, axis=0)])
    trial_gaps = trial_gaps.select((hidden_so_far[trial_gaps.stop, trial_gaps.joint]
                                    > hidden_so_far[trial_gaps.start, trial_gaps.joint])
                                   & ~trial_gaps.whole_clip)
    return hidden, trial_missing, trial_gaps


def validation_weights(trials: Sequence[np.ndarray], truth: np.ndarray, hidden: np.ndarray,
                       trial_gaps: Gaps) -> np.ndarray:
    """Weigh estimates per joint, inversely to their squared error on the trials.

    Parameters
    ----------
    trials
        Per estimate, ``(N, 2) float64``: its values at the points of
        ``trial_gaps.frames()``, in order.
    truth
        ``(T, J, 2) float64``: the tracks, read at the hidden points (the same units as
        ``trials``).
    hidden, trial_gaps
        From :func:`validation_trials`.

    Returns
    -------
    numpy.ndarray
        ``(E, J) float64``: each estimate's weight per joint, summing to 1 over the
        estimates; equal weights for a joint with no hidden point.
    """
    _, trial_frame, trial_joint = trial_gaps.frames()
    scored = hidden[trial_frame, trial_joint]
    seen = truth[trial_frame[scored], trial_joint[scored]]
    errors = np.array([np.bincount(trial_joint[scored],
                                   np.sum((trial[scored] - seen) ** 2, axis=-1),
                                   minlength=hidden.shape[1]) for trial in trials])
    inverse = 1.0 / np.maximum(errors, np.finfo(float).tiny)
    return np.where(hidden.any(axis=0), inverse / inverse.sum(axis=0), 1.0 / len(trials))


def _long_gap_fill(
    local: np.ndarray, filled: np.ndarray, missing: np.ndarray, gaps: Gaps,
    skeleton: Skeleton, rule: str, variance: float, short_gap: int, reach: int,
    bridged: int,
) -> np.ndarray:
    _, frame, joint = gaps.frames()
    blended = filled.copy()
    if rule != "validated":
        blended[frame, joint] = estimate_long_gaps((rule,), local, filled, [(missing, gaps)],
                                                   skeleton, variance, reach,
                                                   bridged)[0][0]
        return blended
    hidden, trial_missing, trial_gaps = validation_trials(missing, gaps, short_gap)
    trials, estimates = estimate_long_gaps(VALIDATED_ESTIMATES, local, filled,
                                           [(trial_missing, trial_gaps), (missing, gaps)],
                                           skeleton, variance, reach, bridged)
    weights = validation_weights(trials, local, hidden, trial_gaps)
    blended[frame, joint] = np.sum(weights[:, joint, None] * np.stack(estimates), axis=0)
    return blended


def palm_gap_fill(
    tracks: np.ndarray, in_palm_frame: np.ndarray, missing: np.ndarray, gaps: Gaps,
    skeleton: Skeleton,
) -> np.ndarray:
    """Fill the gaps of palm points by two rigid-body fills, weighed by validation.

    Both carry a palm point with the other palm points. One holds it still in the palm
    frame (:mod:`~handdb.gapfill.palm_frame`, whose map is fitted to the clip's median palm
    shape); the other carries it from each edge of its gap by the map of the palm points
    seen at that edge and in the frame (:func:`~handdb.gapfill.rigid.carried_points`),
    which follows the palm's shape as it is around the gap: a detector's palm, whose
    points shift against each other as the hand turns, or a palm seen through a pinhole,
    is not one affine shape over a whole clip. They are weighed per joint, as the long
    finger gaps are, by how well each refills observed runs of the joint hidden on purpose
    (:func:`validation_trials`; the palm's map is fitted again without them).

    Parameters
    ----------
    tracks
        ``(T, J, 2) float64``, pixels: the tracks filled from (smoothed), finite where
        observed.
    in_palm_frame
        ``(T, J, 2) float64``, pixels: ``tracks`` with the points of ``gaps`` filled in the
        palm frame and mapped to the image.
    missing
        ``(T, J) bool``: the points to fill from others.
    gaps
        The palm points' gaps, none of them a whole clip.
    skeleton
        The clip's skeleton.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``in_palm_frame`` with the points of ``gaps`` replaced by
        the weighed fill, pixels.
    """
    hidden, trial_missing, trial_gaps = validation_trials(missing, gaps)
    trial_motion = palm_motion(tracks, trial_missing, skeleton)
    if trial_motion is None or not len(trial_gaps):
        return in_palm_frame
    palm = palm_joints(skeleton)
    trial_carried, carried = carried_points(
        [(np.where(trial_missing[..., None], np.nan, tracks), trial_missing, trial_gaps),
         (np.where(missing[..., None], np.nan, tracks), missing, gaps)], palm)
    trial_local = interpolate_gaps(
        np.where(trial_missing[..., None], np.nan, to_palm_frame(tracks, trial_motion)),
        trial_missing, "pchip")
    _, trial_frame, trial_joint = trial_gaps.frames()
    trial_held = to_image(trial_local[trial_frame, trial_joint], trial_motion, trial_frame)
    weights = validation_weights([trial_held, trial_carried], tracks, hidden, trial_gaps)
    _, frame, joint = gaps.frames()
    filled = in_palm_frame.copy()
    filled[frame, joint] = (weights[0, joint, None] * in_palm_frame[frame, joint]
                            + weights[1, joint, None] * carried)
    return filled


def check_placeable(missing: np.ndarray, skeleton: Skeleton, never_seen: np.ndarray) -> None:
    """Refuse a clip that observes too little of the palm to place its never-observed joints.

    A joint never observed is placed from the rest pose fitted to the wrist and finger
    bases a frame observes (:func:`~handdb.gapfill.rigid.place_from_rest_pose`); a clip
    none of whose frames is placeable (:func:`~handdb.gapfill.rigid.placeable_frames`)
    gives no hand to place it on.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    skeleton
        The clip's skeleton.
    never_seen
        ``(K,) int64``: the joints missing in every frame.

    Raises
    ------
    GapFillError
        If ``never_seen`` is not empty and no frame observes enough palm points; the
        message names the joints never observed and the palm points the clip does observe.
    """
    if not never_seen.size or placeable_frames(missing, skeleton).any():
        return
    seen = [skeleton.joints[j]
            for j in np.flatnonzero(palm_joints(skeleton) & ~missing.all(axis=0))]
    names = ", ".join(skeleton.joints[j] for j in never_seen)
    raise GapFillError(
        f"gap filling by 'auto' cannot place {names}: never observed in the clip, they are "
        "placed from the hand model fitted to the wrist and finger bases, and no frame "
        f"observes {MIN_PALM_POINTS} of those (the clip observes "
        f"{', '.join(seen) if seen else 'none of them'}). Map the tool's body parts to the "
        "wrist and the knuckles (\"joint_map\"), lower \"min_confidence\" if the detector "
        "reported them with low confidence, or give the sidecar \"gap_fill\": "
        "{\"method\": \"rigid\"}, which leaves what it cannot place unfilled"
    )


def track_segments(missing: np.ndarray, short_gap: int) -> list[tuple[int, int]]:
    """The runs of frames filled as one track, between frames that stay unfilled.

    Frames that observe no point are bridged like any gap when they form an interior run
    of at most ``short_gap`` frames; runs at the clip's start or end, or longer, give
    nothing to bridge from and split the clip.

    Parameters
    ----------
    missing
        ``(T, J) bool``.
    short_gap
        Longest run of empty frames bridged, frames.

    Returns
    -------
    list of tuple of int
        ``(start, stop)`` of each segment, frames, ``stop`` exclusive, in order.
    """
    runs = find_gaps(np.asarray(missing.all(axis=1))[:, None])
    kept = runs.select(~runs.interior | (runs.length > short_gap))
    unfilled = np.zeros(missing.shape[0], dtype=bool)
    for start, stop in zip(kept.start, kept.stop, strict=True):
        unfilled[start:stop] = True
    segments = find_gaps(~unfilled[:, None])
    return [(int(a), int(b)) for a, b in zip(segments.start, segments.stop, strict=True)]


def fill_auto(
    uv: np.ndarray,
    missing: np.ndarray,
    skeleton: Skeleton,
    *,
    short_gap: int = SHORT_GAP,
    long_gaps: str = "validated",
    variance: float = DEFAULT_VARIANCE,
    bone_lengths: dict[str, float] | None = None,
    scale: float | np.ndarray | None = None,
    smooth: bool = True,
    average_edges: bool = False,
) -> MethodOutput:
    """Fill every gap with the rule that suits it (see the module docstring).

    Parameters
    ----------
    uv, missing, skeleton
        As for every method (see :mod:`handdb.gapfill.registry`).
    short_gap
        Longest interior finger gap, frames, bridged by PCHIP.
    long_gaps
        Rule for longer finger gaps, one of :data:`LONG_GAP_RULES`.
    variance
        Variance share kept by the low-rank model.
    bone_lengths, scale
        Optional 3D bone lengths (child joint -> length, clip units) and the image scale
        (pixels per unit, scalar or ``(T,)``) that bound the projected bones in refinement.
    smooth
        Fill from the observed tracks smoothed against detector jitter
        (:func:`~handdb.denoise.denoise`; the observed points are returned as they
        were), or from the tracks as observed.
    average_edges
        Carry a long finger gap's ``"chain"`` estimate from the mean of the point over the
        frames beside each edge that the smoothing's half-window spans (each carried to
        the edge frame; :func:`~handdb.gapfill.rigid.carry_along_chains_many`), rather
        than from the edge frame alone. Without smoothing it changes nothing. Not the
        default: it helps some clips with detector noise and harms others
        (``benchmarks/RESULTS-gapfill.md``).

    Raises
    ------
    ParameterError
        If ``long_gaps`` is not a rule.
    GapFillError
        If a joint is never observed and no frame observes enough of the palm to place it
        (see :func:`check_placeable`).
    """
    if long_gaps not in LONG_GAP_RULES:
        raise ParameterError(
            f"long_gaps must be one of {', '.join(LONG_GAP_RULES)}; got '{long_gaps}'"
        )
    gaps = find_gaps(missing)
    check_placeable(missing, skeleton, np.unique(gaps.joint[gaps.whole_clip]))
    filled = uv.copy()
    labels = np.zeros(missing.shape, dtype=f"<U{max(map(len, RULE_LABELS))}")
    for start, stop in track_segments(missing, short_gap):
        part = _fill_track(uv[start:stop], missing[start:stop], skeleton, short_gap=short_gap,
                           long_gaps=long_gaps, variance=variance, bone_lengths=bone_lengths,
                           scale=scale[start:stop] if isinstance(scale, np.ndarray) else scale,
                           smooth=smooth, average_edges=average_edges)
        filled[start:stop], labels[start:stop] = part.uv, part.labels
    return MethodOutput(filled, labels=labels)


def _fill_track(
    uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, *, short_gap: int,
    long_gaps: str, variance: float, bone_lengths: dict[str, float] | None,
    scale: float | np.ndarray | None, smooth: bool, average_edges: bool,
) -> MethodOutput:
    """Fill one segment of :func:`track_segments` (the parameters of :func:`fill_auto`).

    A joint the segment never observes is placed from the rest pose in each frame that
    observes enough to fit it, and bridged like any gap across the frames that do not.
    """
    gaps = find_gaps(missing)
    never_seen = np.unique(gaps.joint[gaps.whole_clip])
    smoothed, half = denoise(uv, missing) if smooth else (uv, 0)
    placed = (place_from_rest_pose(smoothed, missing, skeleton, never_seen) if never_seen.size
              else smoothed)
    placed, on_chords = place_on_chords(placed, missing, skeleton, never_seen)
    unknown = missing & ~finite_points(placed)
    motion = palm_motion(smoothed, missing, skeleton)
    local = placed if motion is None else to_palm_frame(placed, motion)

    palm = palm_joints(skeleton)[gaps.joint]
    short = gaps.interior & (gaps.length <= short_gap)
    partial = ~gaps.whole_clip
    by_model = partial & ~palm & ~short

    filled_local = interpolate_gaps(local, unknown, "pchip")
    if by_model.any():
        filled_local = _long_gap_fill(local, filled_local, unknown, gaps.select(by_model),
                                      skeleton, long_gaps, variance, short_gap,
                                      half + 1 if average_edges else 1,
                                      # A gap no longer than the smoothing's half-width is
                                      # interpolated within the span over which Stein's
                                      # risk found the motion smooth: as good as observed.
                                      half)
    filled = np.where(missing[..., None], placed, uv)
    frame, joint = mask_points(unknown)
    filled[frame, joint] = (filled_local[frame, joint] if motion is None
                            else to_image(filled_local[frame, joint], motion, frame))
    if motion is not None and (partial & palm).any():
        filled = palm_gap_fill(placed, filled, unknown, gaps.select(partial & palm), skeleton)

    labels = np.zeros(missing.shape, dtype=f"<U{max(map(len, RULE_LABELS))}")
    for rule, chosen in (("rigid", partial & palm), ("pchip", partial & ~palm & short),
                         (long_gaps, by_model), ("rest-pose", gaps.whole_clip)):
        _, frame, joint = gaps.select(chosen).frames()
        labels[frame, joint] = rule
    labels[on_chords] = "chord"
    # A frame that observes nothing gives the palm frame nothing to be fitted to either:
    # its points are interpolated in the image from the frames around it, the joints
    # never observed from where the hand model placed them there.
    empty = np.asarray(missing.all(axis=1))
    if empty.any():
        bridge = np.zeros_like(missing)
        bridge[empty] = True
        filled[empty] = interpolate_gaps(np.where(bridge[..., None], np.nan, filled), bridge,
                                         "pchip")[empty]
        labels[np.ix_(empty, np.isin(np.arange(missing.shape[1]), never_seen,
                                     invert=True))] = "pchip"
    refined = refine_bone_lengths(filled, missing, skeleton, bone_lengths=bone_lengths,
                                  scale=scale)
    return MethodOutput(refined, labels=labels)
