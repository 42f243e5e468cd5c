"""Marker fitting: accuracy and speed on a held-out synthetic capture and the DHG sample.

Prints, for a synthetic 'rapid' capture (handdb.synthetic: a hand and motion the fitting
model did not generate) with ~1 mm marker noise and occlusion runs leaving about 15 of 21
markers per frame, no bone lengths given:

* the full pipeline (calibration, key frames, eq. 12 refinement, PFIK+F): MPJPE to the
  truth and frames per second;
* least squares against the paper's particle swarm, frame by frame, on the same model;
* a population of hands (seeds 0-5: sizes, proportions, palms, thumb bases and wrist
  points of :func:`handdb.hand.population.sample_shape`): visible-marker residual and MPJPE
  of the full fit per hand;
* on the real DHG sample (all markers present; 6 of 21 hidden a frame): the fit residuals
  and, where markers are hidden, the error to the hidden joints.

Run: ``.venv/bin/python benchmarks/bench_fitting.py [n_frames]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from handdb.hand.model import forward_kinematics
from handdb.hand.skeletons import convert_points, load_skeleton
from handdb.markers.fit import fit_markers
from handdb.markers.solve import track
from handdb.synthetic import synthesize_clip

NOISE_MM = 1.0
HIDDEN_FRACTION = 6.0 / 21.0
MEAN_RUN_FRAMES = 6.0
SOLVER_FRAMES = 30
DHG = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "dhg-sample"


def occlusion_runs(shape: tuple[int, int], hidden: float, mean_run: float,
                   rng: np.random.Generator) -> np.ndarray:
    """``(T, J) bool`` hidden markers: a two-state Markov chain per marker."""
    leave_hidden = 1.0 / mean_run
    enter_hidden = leave_hidden * hidden / (1.0 - hidden)
    state = rng.random(shape[1]) < hidden
    mask = np.empty(shape, dtype=bool)
    for t in range(shape[0]):
        flip = rng.random(shape[1]) < np.where(state, leave_hidden, enter_hidden)
        state = state ^ flip
        mask[t] = state
    return mask


def errors(joints: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return np.linalg.norm(joints - truth, axis=-1)


def held_out(n_frames: int) -> None:
    clip = synthesize_clip("rapid", n_frames, seed=5)
    rng = np.random.default_rng(1)
    hidden = occlusion_runs(clip.xyz.shape[:2], HIDDEN_FRACTION, MEAN_RUN_FRAMES, rng)
    markers = clip.xyz + rng.normal(0.0, NOISE_MM, clip.xyz.shape)
    markers[hidden] = np.nan
    print(f"held-out capture: synthetic '{clip.motion}', {n_frames} frames at {clip.fps:g} "
          f"fps, noise {NOISE_MM} mm, {(~hidden).sum(1).mean():.1f}/21 markers visible")

    start = time.perf_counter()
    fit = fit_markers(markers, hand=clip.hand, units=clip.units)
    seconds = time.perf_counter() - start
    err = errors(fit.joints, clip.xyz)
    truth_lengths = np.array([clip.bone_lengths[b] for b in fit.model.skeleton.bone_names])
    print(f"  full fit (calibration, lsq every frame, PFIK+F): MPJPE {err.mean():.2f} mm "
          f"(visible {err[~hidden].mean():.2f}, hidden {err[hidden].mean():.2f}, "
          f"95th pct {np.percentile(err, 95):.2f}), {n_frames / seconds:.2f} frames/s "
          f"({seconds:.1f} s)")
    print(f"  calibrated bone lengths: mean |error| "
          f"{np.abs(fit.model.bone_lengths - truth_lengths).mean():.2f} mm, "
          f"max {np.abs(fit.model.bone_lengths - truth_lengths).max():.2f} mm")

    start = time.perf_counter()
    stepped = fit_markers(markers, hand=clip.hand, units=clip.units, key_step=4)
    seconds = time.perf_counter() - start
    err = errors(stepped.joints, clip.xyz)
    print(f"  key step 4 with eq. 12 refinement between: MPJPE {err.mean():.2f} mm "
          f"(95th pct {np.percentile(err, 95):.2f}), {n_frames / seconds:.2f} frames/s")

    model = fit.model
    frames = slice(0, SOLVER_FRAMES)
    for solver in ("lsq", "pso"):
        start = time.perf_counter()
        poses = track(model, markers[frames], solver=solver, start=fit.poses[0],
                      rng=np.random.default_rng(0))
        seconds = time.perf_counter() - start
        err = errors(forward_kinematics(model, poses), clip.xyz[frames])
        print(f"  per-frame {solver}: MPJPE {err.mean():.2f} mm over {SOLVER_FRAMES} frames, "
              f"{SOLVER_FRAMES / seconds:.2f} frames/s")


POPULATION_SEEDS = range(6)
POPULATION_FRAMES = 60


def population() -> None:
    rows = []
    for seed in POPULATION_SEEDS:
        clip = synthesize_clip("random", POPULATION_FRAMES, seed=seed)
        rng = np.random.default_rng(seed)
        hidden = occlusion_runs(clip.xyz.shape[:2], HIDDEN_FRACTION, MEAN_RUN_FRAMES, rng)
        markers = clip.xyz + rng.normal(0.0, NOISE_MM, clip.xyz.shape)
        markers[hidden] = np.nan
        fit = fit_markers(markers, hand=clip.hand, units=clip.units)
        err = errors(fit.joints, clip.xyz)
        rows.append((np.nanmean(fit.residual), err.mean(), err[hidden].mean()))
        print(f"population hand {seed}: visible-marker residual {rows[-1][0]:.2f} mm, MPJPE "
              f"{rows[-1][1]:.2f} mm (hidden joints {rows[-1][2]:.2f})")
    mean = np.mean(rows, axis=0)
    print(f"population mean: visible residual {mean[0]:.2f} mm, MPJPE {mean[1]:.2f} mm, "
          f"hidden {mean[2]:.2f} mm")


def dhg_sample() -> None:
    path = DHG / "skeletons_world.txt"
    if not path.is_file():
        print("DHG sample: absent, skipped")
        return
    markers = np.loadtxt(path).reshape(-1, 22, 3) * 1000.0
    rng = np.random.default_rng(0)
    hidden = np.zeros(markers.shape[:2], dtype=bool)
    for frame in hidden:
        frame[rng.choice(np.arange(1, 22), 6, replace=False)] = True
    partial = np.where(hidden[..., None], np.nan, markers)
    fit = fit_markers(partial, skeleton="dhg22")
    err = errors(fit.joints, markers)
    print(f"DHG sample on dhg22, 6 of 22 joints hidden a frame: visible residual "
          f"{np.nanmean(fit.residual):.1f} mm, MPJPE {err.mean():.1f} mm (hidden "
          f"{err[hidden].mean():.1f} mm)")
    markers = convert_points(markers, load_skeleton("dhg22"), load_skeleton("mediapipe21"))
    for hand in ("right", "left"):
        start = time.perf_counter()
        fit = fit_markers(markers, hand=hand, units="mm")
        seconds = time.perf_counter() - start
        residual = fit.residual
        worst = fit.model.skeleton.joints[int(np.nanargmax(np.nanmean(residual, 0)))]
        print(f"DHG sample as a {hand} hand: {len(markers)} frames, marker-to-joint residual "
              f"mean {np.nanmean(residual):.1f} mm, median {np.nanmedian(residual):.1f} mm, "
              f"95th pct {np.nanpercentile(residual, 95):.1f} mm; worst joint {worst}; "
              f"{len(markers) / seconds:.2f} frames/s")


if __name__ == "__main__":
    held_out(int(sys.argv[1]) if len(sys.argv) > 1 else 150)
    population()
    dhg_sample()
