"""Bone-length calibration against the per-bone median: accuracy and time.

Synthetic: a mediapipe21 hand of known bone lengths (Buchholz et al. 1992 proportions of
a 185 mm hand) in random poses, 1.5 mm noise per axis on every joint and 10 % of the
joints thrown off by 20 mm; error of each estimate against the known lengths.
Real: the DHG-14/28 sample in ../shared/data/dhg-sample (skipped when absent): the two
estimates per bone side by side, with the per-frame spread and the fit's residual.

Run: ``.venv/bin/python benchmarks/bone_length_calibration.py``
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from handdb.anthropometry import hand_length_proportions
from handdb.length_calibration import calibrate_bone_lengths, frame_bone_lengths
from handdb.ratios import joint_ratios, table1_measurements
from handdb.skeletons import load_skeleton

DHG_SAMPLE = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "dhg-sample"
HAND_LENGTH_MM = 185.0
THUMB_BASE_MM = 28.0
N_FRAMES = 200
NOISE_MM = 1.5
OUTLIER_SHARE = 0.1
OUTLIER_MM = 20.0
SEEDS = range(10)


def synthetic_capture(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Noisy joint positions ``(T, J, 3)`` mm of random poses, and the true lengths."""
    skeleton = load_skeleton("mediapipe21")
    lengths = hand_length_proportions(skeleton) * HAND_LENGTH_MM
    lengths[skeleton.index("thumb_cmc")] = THUMB_BASE_MM
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(N_FRAMES, skeleton.n_joints, 3))
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    xyz = np.zeros((N_FRAMES, skeleton.n_joints, 3))
    for joint in range(1, skeleton.n_joints):
        xyz[:, joint] = xyz[:, skeleton.parents[joint]] + lengths[joint] * directions[:, joint]
    noisy = xyz + rng.normal(0.0, NOISE_MM, xyz.shape)
    thrown = rng.random(xyz.shape[:2]) < OUTLIER_SHARE
    noisy[thrown] += rng.normal(0.0, OUTLIER_MM, (thrown.sum(), 3))
    return noisy, lengths


def synthetic_report() -> None:
    skeleton = load_skeleton("mediapipe21")
    errors: dict[str, list[np.ndarray]] = {"median": [], "calibrated": []}
    seconds = []
    for seed in SEEDS:
        noisy, truth = synthetic_capture(seed)
        start = time.perf_counter()
        fit = calibrate_bone_lengths(noisy, skeleton)
        seconds.append(time.perf_counter() - start)
        errors["median"].append(np.abs(fit.median - truth)[1:])
        errors["calibrated"].append(np.abs(fit.lengths - truth)[1:])
    print(f"synthetic, {len(SEEDS)} captures of {N_FRAMES} frames, {NOISE_MM} mm noise, "
          f"{OUTLIER_SHARE:.0%} outliers of {OUTLIER_MM} mm")
    for name, values in errors.items():
        stacked = np.stack(values)
        print(f"  {name:10s} mean abs error {stacked.mean():.3f} mm, "
              f"worst bone {stacked.max():.3f} mm")
    print(f"  calibration time {np.median(seconds) * 1000:.0f} ms per capture (median)")


def dhg_report() -> None:
    path = DHG_SAMPLE / "skeletons_world.txt"
    if not path.is_file():
        print(f"DHG sample absent ({path}); skipped")
        return
    skeleton = load_skeleton("dhg22")
    xyz = np.loadtxt(path).reshape(-1, skeleton.n_joints, 3) * 1000.0
    ratios = joint_ratios(table1_measurements())
    free = calibrate_bone_lengths(xyz, skeleton, ratios, weight=0.0)
    prior = calibrate_bone_lengths(xyz, skeleton, ratios)
    spread = np.full(skeleton.n_joints, np.nan)
    spread[1:] = frame_bone_lengths(xyz, skeleton)[:, 1:].std(axis=0)
    print(f"DHG sample, {xyz.shape[0]} frames (mm): per-bone median, robust fit without "
          "and with the X-ray prior (deviation from the X-ray ratio in its std)")
    print(f"  {'bone':12s} {'sd':>6s} {'median':>7s} {'robust':>7s} {'+prior':>7s} "
          f"{'resid':>6s} {'dev':>6s} {'dev+p':>6s}")
    for j in range(1, skeleton.n_joints):
        print(f"  {skeleton.joints[j]:12s} {spread[j]:6.2f} {free.median[j]:7.2f} "
              f"{free.lengths[j]:7.2f} {prior.lengths[j]:7.2f} {prior.residuals[j]:6.2f} "
              f"{free.prior_deviation[j]:6.2f} {prior.prior_deviation[j]:6.2f}")
    print(f"  mean |robust - median| {np.nanmean(np.abs(free.lengths - free.median)):.2f} mm; "
          f"mean |deviation| {np.nanmean(np.abs(free.prior_deviation)):.2f} -> "
          f"{np.nanmean(np.abs(prior.prior_deviation)):.2f} std with the prior")


if __name__ == "__main__":
    synthetic_report()
    dhg_report()
