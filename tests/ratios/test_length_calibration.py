import numpy as np
import pytest

from handdb.length_calibration import calibrate_bone_lengths, frame_bone_lengths
from handdb.ratios import bone_ratios, joint_ratios, table1_measurements
from handdb.skeletons import load_skeleton

#: Synthetic capture: frames, per-axis noise on every joint (mm), share of joints thrown
#: off by a gross error, and that error's per-axis spread (mm).
N_FRAMES = 200
NOISE_MM = 1.5
OUTLIER_SHARE = 0.1
OUTLIER_MM = 20.0

#: Tolerance on the worst bone. The difference of two noisy ends has per-axis spread
#: 1.5 * sqrt(2) = 2.1 mm, so over 200 frames a robust estimate of one bone has a
#: standard error of about 2.1 / sqrt(200) * 1.2 = 0.18 mm; the worst of 20 bones stays
#: within about 3 standard errors, 0.55 mm. 1 mm leaves room for the outliers.
WORST_BONE_MM = 1.0


@pytest.fixture(scope="module")
def ratios():
    return joint_ratios(table1_measurements())


def _noisy_capture(hand, seed: int):
    skeleton = load_skeleton("mediapipe21")
    rng = np.random.default_rng(seed)
    xyz = hand.posed(skeleton, hand.true_lengths(skeleton), rng.uniform(0.0, 1.4, N_FRAMES))
    noisy = xyz + rng.normal(0.0, NOISE_MM, xyz.shape)
    thrown = rng.random(xyz.shape[:2]) < OUTLIER_SHARE
    noisy[thrown] += rng.normal(0.0, OUTLIER_MM, (thrown.sum(), 3))
    return skeleton, noisy


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_recovers_known_lengths_better_than_the_median(seed, hand):
    skeleton, noisy = _noisy_capture(hand, seed)
    truth = hand.true_lengths(skeleton)
    result = calibrate_bone_lengths(noisy, skeleton)
    assert result.converged
    error = np.abs(result.lengths - truth)[1:]
    median_error = np.abs(result.median - truth)[1:]
    assert error.max() < WORST_BONE_MM
    # The median keeps the noise's lengthening bias and the outliers' pull.
    assert error.mean() < 0.6 * median_error.mean()
    assert (result.n_frames[1:] == N_FRAMES).all()


def test_plain_least_squares_is_thrown_by_outliers(hand):
    skeleton, noisy = _noisy_capture(hand, 0)
    truth = hand.true_lengths(skeleton)
    plain = calibrate_bone_lengths(noisy, skeleton, loss="linear")
    robust = calibrate_bone_lengths(noisy, skeleton)
    assert np.abs(plain.lengths - truth)[1:].mean() > 3 * np.abs(robust.lengths - truth)[1:].mean()


def test_exact_frames_give_exact_lengths(hand):
    skeleton = load_skeleton("mediapipe21")
    xyz = hand.posed(skeleton, hand.true_lengths(skeleton), np.linspace(0, 1, 10))
    result = calibrate_bone_lengths(xyz, skeleton)
    np.testing.assert_allclose(result.lengths[1:], hand.true_lengths(skeleton)[1:], rtol=1e-4)


def test_prior_weight_moves_phalanges_to_the_xray_ratios(ratios, hand):
    skeleton, noisy = _noisy_capture(hand, 1)
    free = calibrate_bone_lengths(noisy, skeleton, ratios, weight=0.0)
    strong = calibrate_bone_lengths(noisy, skeleton, ratios, weight=1e3)
    unregularised = calibrate_bone_lengths(noisy, skeleton)
    np.testing.assert_allclose(free.lengths, unregularised.lengths, rtol=1e-6)
    mean, _ = bone_ratios(skeleton, ratios)
    phalanges = np.isfinite(mean)
    assert np.abs(strong.prior_deviation[phalanges]).max() < 0.1
    assert np.abs(free.prior_deviation[phalanges]).max() > 1.0
    palm = ~phalanges
    palm[skeleton.root] = False
    np.testing.assert_allclose(strong.lengths[palm], free.lengths[palm], rtol=1e-3)


def test_missing_joints_are_skipped(hand):
    skeleton, noisy = _noisy_capture(hand, 2)
    noisy[:50, skeleton.index("ring_tip")] = np.nan
    noisy[:, skeleton.index("little_tip")] = np.nan
    result = calibrate_bone_lengths(noisy, skeleton)
    assert result.n_frames[skeleton.index("ring_tip")] == N_FRAMES - 50
    assert result.n_frames[skeleton.index("little_tip")] == 0
    assert np.isnan(result.lengths[skeleton.index("little_tip")])
    assert np.isfinite(result.lengths[skeleton.index("ring_tip")])


def test_negative_weight_is_refused(hand):
    skeleton, noisy = _noisy_capture(hand, 0)
    with pytest.raises(ValueError, match="weight"):
        calibrate_bone_lengths(noisy, skeleton, weight=-1.0)


def test_real_noisy_capture(dhg_sample, ratios):
    skeleton = load_skeleton("dhg22")
    xyz = np.loadtxt(dhg_sample).reshape(-1, skeleton.n_joints, 3) * 1000.0  # m -> mm
    per_frame = frame_bone_lengths(xyz, skeleton)[:, 1:]
    free = calibrate_bone_lengths(xyz, skeleton, ratios, weight=0.0)
    assert free.converged and np.isfinite(free.lengths[1:]).all()
    quartiles = np.percentile(per_frame, [25, 75], axis=0)
    assert ((free.lengths[1:] >= quartiles[0]) & (free.lengths[1:] <= quartiles[1])).all()
    # Noise lengthens bones on average, so the fit sits below the per-bone median.
    assert (free.lengths[1:] - free.median[1:]).mean() < 0
    assert (free.residuals[1:] < per_frame.std(axis=0)).all()

    regularised = calibrate_bone_lengths(xyz, skeleton, ratios)
    phalanges = np.isfinite(bone_ratios(skeleton, ratios)[0])
    deviation = np.abs(regularised.prior_deviation[phalanges]).mean()
    assert deviation < 0.5 * np.abs(free.prior_deviation[phalanges]).mean()
    deciles = np.percentile(per_frame, [10, 90], axis=0)
    lengths = regularised.lengths[1:]
    assert ((lengths >= deciles[0]) & (lengths <= deciles[1])).all()
