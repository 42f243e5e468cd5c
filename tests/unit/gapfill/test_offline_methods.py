import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from handdb.gapfill import METHODS, UNFILLED, fill_gaps
from handdb.gapfill.auto import (
    SHORT_GAP,
    VALIDATION_GAPS,
    edge_validation_mask,
    estimate_long_gaps,
    validation_mask,
)
from handdb.gapfill.gaps import find_gaps
from handdb.gapfill.interpolate import interpolate_gaps
from handdb.gapfill.lowrank import lowrank_reconstruct
from handdb.gapfill.refine import bone_bounds, refine_bone_lengths
from handdb.gapfill.regression import regression_fill
from handdb.gapfill.rest_pose import rest_pose_2d
from handdb.gapfill.rigid import carry_along_chains, carry_along_chains_many, palm_joints
from handdb.hand.skeletons import load_skeleton


def _hide(n_frames, n_joints, gaps):
    observed = np.ones((n_frames, n_joints), dtype=bool)
    for joint, start, stop in gaps:
        observed[start:stop, joint] = False
    return observed


def _polynomial_tracks(degree, n_frames=60, n_joints=3):
    t = np.linspace(-1, 1, n_frames)
    rng = np.random.default_rng(degree)
    coefficients = rng.normal(size=(degree + 1, n_joints, 2)) * 50
    return np.einsum("d t, d j k -> t j k", np.vander(t, degree + 1).T, coefficients)


@pytest.mark.parametrize(("kind", "degree"), [("linear", 1), ("pchip", 1), ("cubic", 3)])
def test_interpolation_reproduces_its_polynomials(kind, degree):
    uv = _polynomial_tracks(degree)
    missing = ~_hide(60, 3, [(0, 10, 25), (1, 40, 41), (2, 5, 50)])
    filled = interpolate_gaps(np.where(missing[..., None], np.nan, uv), missing, kind)
    assert np.allclose(filled, uv, atol=1e-9)


def test_linear_interpolation_does_not_reproduce_a_cubic():
    uv = _polynomial_tracks(3)
    missing = ~_hide(60, 3, [(0, 10, 25)])
    filled = interpolate_gaps(np.where(missing[..., None], np.nan, uv), missing, "linear")
    assert np.abs(filled - uv).max() > 1.0


def test_max_gap_leaves_longer_gaps_unfilled_and_flagged(mediapipe):
    uv = np.tile(np.arange(30.0)[:, None, None], (1, mediapipe.n_joints, 2))
    observed = _hide(30, mediapipe.n_joints, [(5, 2, 5), (6, 10, 25)])
    result = fill_gaps(uv, observed, mediapipe, "pchip", max_gap=5)
    assert result.filled[2:5, 5].all() and not result.filled[10:25, 6].any()
    assert np.isnan(result.uv[10:25, 6]).all()
    assert [(f.joint, f.start, f.stop) for f in result.flags_of(UNFILLED)] == [
        ("index_pip", 10, 25)]


def test_lowrank_recovers_a_low_rank_signal():
    rng = np.random.default_rng(4)
    t = np.arange(300) / 30
    latent = np.stack([np.sin(2.1 * t), np.cos(3.3 * t + 1), np.sin(0.7 * t) ** 3], axis=1)
    uv = (latent @ rng.normal(size=(3, 20 * 2)) * 40 + 200).reshape(300, 20, 2)
    observed = _hide(300, 20, [(j, 20 + 11 * j, 60 + 11 * j) for j in range(0, 20, 2)])
    missing = ~observed
    hidden = np.where(missing[..., None], np.nan, uv)
    model = lowrank_reconstruct(hidden, missing)
    linear = interpolate_gaps(hidden, missing, "linear")
    lowrank_error = np.abs(model - uv)[missing].max()
    linear_error = np.abs(linear - uv)[missing].max()
    assert lowrank_error < 0.5
    assert lowrank_error < linear_error / 20


def test_rigid_fill_recovers_a_point_moving_with_the_palm(rapid_clip, mediapipe):
    n_frames = 80
    rest = rapid_clip.uv[0]
    angle = np.linspace(0, 1.2, n_frames)
    rotation = np.stack([np.stack([np.cos(angle), -np.sin(angle)], -1),
                         np.stack([np.sin(angle), np.cos(angle)], -1)], -2)
    stretch = np.array([[1.0, 0.0], [0.0, 0.7]])                  # the palm tilts away
    uv = np.einsum("tij,jk,nk->tni", rotation, stretch, rest - rest[0]) + np.linspace(
        0, 90, n_frames)[:, None, None]
    j = mediapipe.index("ring_mcp")
    assert palm_joints(mediapipe)[j]
    observed = _hide(n_frames, mediapipe.n_joints, [(j, 20, 60)])
    for method in ("rigid", "auto"):
        filled = fill_gaps(uv, observed, mediapipe, method).uv
        assert np.allclose(filled[20:60, j], uv[20:60, j], atol=1e-6), method


def test_edges_and_a_never_seen_joint_are_filled_and_flagged(rapid_clip, mediapipe):
    uv = rapid_clip.uv[:120]
    tip, pip, wrist = (mediapipe.index(n) for n in ("index_tip", "middle_pip", "wrist"))
    observed = _hide(120, mediapipe.n_joints, [(tip, 0, 30), (pip, 90, 120), (wrist, 0, 120)])
    result = fill_gaps(uv, observed, mediapipe)
    assert result.filled[~observed].all() and np.isfinite(result.uv).all()
    kinds = {(f.joint, f.kind) for f in result.flags}
    assert {("index_tip", "leading"), ("middle_pip", "trailing"), ("wrist", "whole_clip")} <= kinds
    hand_size = np.ptp(uv[0], axis=0).max()
    assert np.linalg.norm(result.uv[:, wrist] - uv[:, wrist], axis=-1).max() < hand_size / 2
    assert set(result.fill_method[~observed]) <= {"rigid", "pchip", "validated", "rest-pose"}
    assert (result.fill_method[:, wrist] == "rest-pose").all()


@pytest.mark.parametrize("n_frames", [12, 31, 33, 70])
def test_default_bridges_a_long_finger_gap_in_a_clip_of_few_blocks(n_frames, rapid_clip,
                                                                    mediapipe):
    uv = rapid_clip.uv[:n_frames]
    tip = mediapipe.index("index_tip")
    observed = _hide(n_frames, mediapipe.n_joints, [(tip, 1, n_frames - 1)])
    result = fill_gaps(uv, observed, mediapipe)
    assert result.filled[~observed].all()
    assert set(result.fill_method[~observed]) == {"validated"}
    hand_size = np.ptp(uv[0], axis=0).max()
    assert np.linalg.norm(result.uv[~observed] - uv[~observed], axis=-1).max() < hand_size / 2


@pytest.mark.parametrize("method", sorted(METHODS))
def test_inputs_are_never_mutated(method, rapid_clip, mediapipe):
    uv = rapid_clip.uv[:60].copy()
    observed = _hide(60, mediapipe.n_joints, [(3, 0, 5), (8, 10, 30), (12, 50, 60)])
    uv[~observed] = np.nan
    uv_before, observed_before = uv.copy(), observed.copy()
    result = fill_gaps(uv, observed, mediapipe, method)
    assert np.array_equal(uv, uv_before, equal_nan=True)
    assert np.array_equal(observed, observed_before)
    assert np.array_equal(result.uv[observed], uv[observed])


def test_refinement_pulls_a_filled_point_back_onto_its_bone(mediapipe):
    uv = np.zeros((3, mediapipe.n_joints, 2))
    uv[:, :, 1] = -np.arange(mediapipe.n_joints) * 10.0             # every bone 10 px or more
    tip, dip = mediapipe.index("index_tip"), mediapipe.index("index_dip")
    uv[:, tip] = uv[:, dip] + [0.0, -20.0]
    missing = np.zeros((3, mediapipe.n_joints), dtype=bool)
    missing[2, tip] = True
    uv[2, tip] = uv[2, dip] + [0.0, -60.0]                         # filled three times too long
    refined = refine_bone_lengths(uv, missing, mediapipe)
    assert np.isclose(np.linalg.norm(refined[2, tip] - refined[2, dip]), 20.0 * 1.05)
    assert np.array_equal(refined[~missing], uv[~missing])
    bounded = refine_bone_lengths(uv, missing, mediapipe, bone_lengths={"index_tip": 4.0},
                                  scale=2.5)
    assert np.isclose(np.linalg.norm(bounded[2, tip] - bounded[2, dip]), 10.0)


def test_regression_recovers_a_joint_that_follows_the_others():
    rng = np.random.default_rng(2)
    t = np.arange(200) / 30
    drivers = np.stack([np.sin(1.7 * t), np.cos(2.9 * t)], axis=1) @ rng.normal(size=(2, 8))
    uv = drivers.reshape(200, 4, 2) * 30
    uv = np.concatenate([uv, (uv[:, :2] @ [[0.5, -0.2], [0.3, 0.8]]).sum(1, keepdims=True)], 1)
    missing = np.zeros((200, 5), dtype=bool)
    missing[60:120, 4] = True
    gaps = find_gaps(missing)
    filled = regression_fill(np.where(missing[..., None], np.nan, uv), missing, gaps,
                             np.ones(5, dtype=bool))
    assert np.abs(filled[60:120, 4] - uv[60:120, 4]).max() < 0.05 * np.ptp(uv[:, 4])
    assert np.array_equal(filled[~missing], uv[~missing])


def test_pchip_on_the_gaps_neighbourhood_equals_scipy_on_every_sample():
    rng = np.random.default_rng(0)
    uv = np.cumsum(rng.normal(size=(500, 3, 2)), axis=0)
    missing = rng.random((500, 3)) < 0.1
    missing[:4, 1] = True
    missing[-7:, 2] = True
    filled = interpolate_gaps(np.where(missing[..., None], np.nan, uv), missing, "pchip")
    frames = np.arange(500)
    for j in range(3):
        known = ~missing[:, j]
        at = np.clip(frames[~known], frames[known][0], frames[known][-1])
        expected = PchipInterpolator(frames[known], uv[known, j])(at)
        assert np.allclose(filled[~known, j], expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("n_seen", [1, 2, 3, 4])
def test_pchip_with_few_samples_equals_scipy_and_holds_the_ends(n_seen):
    rng = np.random.default_rng(n_seen)
    uv = rng.normal(size=(40, 1, 2)) * 10
    seen_frames = np.sort(rng.choice(np.arange(3, 37), size=n_seen, replace=False))
    missing = np.ones((40, 1), dtype=bool)
    missing[seen_frames, 0] = False
    filled = interpolate_gaps(np.where(missing[..., None], np.nan, uv), missing, "pchip")
    at = np.clip(np.arange(40), seen_frames[0], seen_frames[-1])
    if n_seen < 3:
        expected = np.stack([np.interp(at, seen_frames, uv[seen_frames, 0, k]) for k in range(2)],
                            axis=-1)
    else:
        expected = PchipInterpolator(seen_frames, uv[seen_frames, 0])(at)
    assert np.allclose(filled[:, 0], expected, rtol=0, atol=1e-12)


def test_validation_runs_are_observed_runs_as_long_as_the_joints_median_gap():
    rng = np.random.default_rng(4)
    missing = np.zeros((300, 5), dtype=bool)
    for joint, (start, lengths) in enumerate([(10, (12, 20, 40)), (40, (9, 9)), (0, (15,))]):
        for length in lengths:
            missing[start:start + length, joint] = True
            start += length + int(rng.integers(20, 60))
    gaps = find_gaps(missing)
    hidden = validation_mask(missing, gaps)
    assert not (hidden & missing).any() and not hidden[:, 3:].any()
    runs = find_gaps(hidden)
    assert np.bincount(runs.joint).max() <= VALIDATION_GAPS
    assert set(runs.length[runs.joint == 0]) == {20} and set(runs.length[runs.joint == 1]) == {9}
    around = np.pad(missing | hidden, ((1, 1), (0, 0)), constant_values=True)
    assert not around[runs.start, runs.joint].any()          # observed just before each run
    assert not around[runs.stop + 1, runs.joint].any()       # and just after it


def test_edge_validation_hides_as_many_frames_beside_an_edge_gap_as_it_has():
    missing = np.zeros((100, 5), dtype=bool)
    missing[80:, 0] = True                  # trailing, 20 frames
    missing[:15, 1] = True                  # leading, 15 frames
    missing[:70, 2] = True                  # leading, longer than the run after it
    missing[90:, 2] = True
    missing[40:50, 3] = True                # interior: no edge run
    missing[:, 4] = True                    # whole clip: none
    gaps = find_gaps(missing)
    hidden = edge_validation_mask(missing, gaps)
    assert not (hidden & missing).any()
    assert np.flatnonzero(hidden[:, 0]).tolist() == list(range(60, 80))
    assert np.flatnonzero(hidden[:, 1]).tolist() == list(range(15, 30))
    # the run 70-89 between two edge gaps is split, its middle frame (80) observed
    assert np.flatnonzero(hidden[:, 2]).tolist() == [*range(70, 80), *range(81, 90)]
    assert not hidden[:, 3:].any()


def test_edge_validation_reaches_across_a_short_dropout_to_extrapolate_as_far_as_the_gap():
    missing = np.zeros((100, 2), dtype=bool)
    missing[52:, 0] = True                  # trailing, 48 frames
    missing[45:47, 0] = True                # a detector's dropout just before it
    missing[20:40, 1] = True                # an interior gap longer than a dropout
    missing[60:, 1] = True                  # trailing, 40 frames
    gaps = find_gaps(missing)
    hidden = edge_validation_mask(missing, gaps, bridged=SHORT_GAP)
    assert not (hidden & missing).any()
    # the trial runs across the dropout, from frame 4 (48 frames before the gap)
    assert np.flatnonzero(hidden[:, 0]).tolist() == [*range(4, 45), *range(47, 52)]
    # a gap longer than a dropout still ends the run
    assert np.flatnonzero(hidden[:, 1]).tolist() == list(range(41, 60))
    # cut at the dropout, the trial would extrapolate 5 frames for a 48-frame gap
    assert np.flatnonzero(edge_validation_mask(missing, gaps)[:, 0]).tolist() == list(
        range(48, 52))


def test_chain_fill_from_averaged_edges_holds_less_of_the_edge_noise(mediapipe):
    n_frames, trailing = 80, 50
    t = np.linspace(0.0, 1.0, n_frames)
    angle, scale = 1.5 * t, 1.0 + 0.5 * t
    cos, sin = scale * np.cos(angle), scale * np.sin(angle)
    rotation = np.stack([np.stack([cos, -sin], axis=-1), np.stack([sin, cos], axis=-1)], axis=1)
    uv = 3.0 * rest_pose_2d(mediapipe) @ np.swapaxes(rotation, 1, 2) + np.stack(
        [200 * t, 50 * t], axis=-1)[:, None]
    tips = [mediapipe.index(f"{finger}_tip") for finger in ("index", "middle", "ring", "little")]
    missing = np.zeros((n_frames, mediapipe.n_joints), dtype=bool)
    missing[trailing:, tips] = True
    gaps = find_gaps(missing)
    exact = carry_along_chains_many(uv, [(missing, gaps)], mediapipe, [np.full(len(gaps), 9)])
    assert np.allclose(exact[0], uv, rtol=0, atol=1e-9)     # the mean of exact carries
    noisy = uv.copy()
    noisy[:trailing, tips] += np.random.default_rng(0).normal(0.0, 1.0, (trailing, 4, 2))
    errors = [np.sqrt(np.mean((carry_along_chains_many(
        noisy, [(missing, gaps)], mediapipe, [np.full(len(gaps), reach)])[0]
        - uv)[trailing:, tips] ** 2)) for reach in (1, 9)]
    # the tips are noisy, their carriers exact: the mean of 9 frames holds a third of it
    assert errors[1] < 0.5 * errors[0]


def test_regression_keeps_a_predictor_across_a_dropout_within_the_gap(mediapipe):
    n_frames = 200
    t = np.linspace(0.0, 4.0 * np.pi, n_frames)[:, None, None]
    rng = np.random.default_rng(3)
    phase, size = rng.uniform(0, 2 * np.pi, (2, 1, 21, 2))
    uv = 100.0 + 30.0 * rng.uniform(0.5, 1.5, (1, 21, 2)) * np.sin(t * (1 + size) + phase)
    tip, predictor = mediapipe.index("index_tip"), mediapipe.index("middle_tip")
    uv[:, tip] = uv[:, predictor] @ np.array([[0.8, -0.3], [0.4, 1.1]]) + 20.0
    fingers = np.flatnonzero(~palm_joints(mediapipe))
    missing = np.zeros((n_frames, mediapipe.n_joints), dtype=bool)
    missing[80:130, tip] = True
    for k, joint in enumerate(j for j in fingers if j != tip):
        missing[85 + 2 * k, joint] = True          # every finger predictor drops a frame
    gaps = find_gaps(missing).select(find_gaps(missing).joint == tip)
    filled = interpolate_gaps(np.where(missing[..., None], np.nan, uv), missing, "pchip")
    truth = uv[80:130, tip]
    kept, = estimate_long_gaps(("regression",), uv, filled, [(missing, gaps)], mediapipe,
                               bridged=1)[0]
    dropped, = estimate_long_gaps(("regression",), uv, filled, [(missing, gaps)],
                                  mediapipe)[0]
    errors = [np.sqrt(np.mean(np.sum((estimate - truth) ** 2, axis=-1)))
              for estimate in (kept, dropped)]
    # kept: the tip follows its predictor (the other predictors' dropped frames are
    # interpolated); dropped: no predictor seen throughout, the chain's estimate
    assert errors[0] < 2.0 and errors[1] > 10 * errors[0]


def _refine_bone_by_bone(uv, missing, skeleton, bounds):
    """The refinement's definition: each bone in joint order, pulling its filled end."""
    refined = uv.copy()
    for b, (parent, child) in enumerate(skeleton.bones):
        for t in np.flatnonzero(missing[:, child] | missing[:, parent]):
            bone = refined[t, child] - refined[t, parent]
            length = np.hypot(*bone)
            if length > bounds[t, b]:
                bone = bone * bounds[t, b] / length
                if missing[t, child]:
                    refined[t, child] = refined[t, parent] + bone
                else:
                    refined[t, parent] = refined[t, child] - bone
    return refined


@pytest.mark.parametrize("name", ["mediapipe21", "thesis21", "dhg22"])
def test_refinement_by_rounds_equals_bone_by_bone(name):
    skeleton = load_skeleton(name)
    rng = np.random.default_rng(7)
    uv = rng.normal(size=(60, skeleton.n_joints, 2)) * 40
    missing = rng.random((60, skeleton.n_joints)) < 0.3
    missing[::3, skeleton.root] = True
    uv[::3, skeleton.root] += 500.0                         # filled far off: every bone pulls
    bounds = bone_bounds(uv, missing, skeleton)
    expected = _refine_bone_by_bone(uv, missing, skeleton, bounds)
    assert np.allclose(refine_bone_lengths(uv, missing, skeleton), expected, atol=1e-9)


def test_chain_fill_is_exact_for_a_hand_moving_by_similarities(mediapipe):
    n_frames = 80
    t = np.linspace(0.0, 1.0, n_frames)
    angle, scale = 1.5 * t, 1.0 + 0.5 * t
    cos, sin = scale * np.cos(angle), scale * np.sin(angle)
    rotation = np.stack([np.stack([cos, -sin], axis=-1), np.stack([sin, cos], axis=-1)], axis=1)
    uv = rest_pose_2d(mediapipe) @ np.swapaxes(rotation, 1, 2) + np.stack(
        [200 * t, 50 * t], axis=-1)[:, None]
    missing = np.zeros((n_frames, mediapipe.n_joints), dtype=bool)
    for name, (start, stop) in {"index_pip": (10, 40), "index_dip": (5, 50),
                                "index_tip": (0, 30), "ring_tip": (60, 80)}.items():
        missing[start:stop, mediapipe.index(name)] = True
    hidden = np.where(missing[..., None], np.nan, uv)
    filled = carry_along_chains(hidden, missing, find_gaps(missing), mediapipe)
    assert np.allclose(filled, uv, rtol=0, atol=1e-9)
