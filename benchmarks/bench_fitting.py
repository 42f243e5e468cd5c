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
  and, where markers are hidden, the error to the hidden joints;
* on the InterHand2.6M hands (real 3D hands annotated from many views, one frame each,
  held out of all marker-fit tuning): each hand as a rigid pseudo-clip
  (:func:`tests.support.real_data.pseudo_clip`, 60 frames) with the same marker noise and
  occlusion runs, then with every marker seen: visible residual, all-joint MPJPE and the
  hidden joints' error per hand;
* on the Qualisys glove (13 real markers on a hand: backs of the hand, finger middles and
  tips, named as the joints they sit nearest, :data:`gapfill_datasets.GLOVE_MARKERS`):
  the visible residual per frame of a few clips; the glove carries no truth for the joints
  it does not mark.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fitting.py [n_frames]
[sections] [limit_weight]`` with ``sections`` a comma-separated subset of :data:`SECTIONS`
(default all) and ``limit_weight`` the calibration's weight of joint angles beyond the
bounds (mm/rad, default: weighed only where the tracker cannot reach the free calibration,
:func:`handdb.markers.calibration.calibrate_reachable`; the held-out capture always runs the
default).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from gapfill_datasets import GLOVE, GLOVE_MARKERS, GLOVE_STEP, glove_markers  # noqa: E402

from handdb.hand.model import forward_kinematics  # noqa: E402
from handdb.hand.skeletons import convert_points, load_skeleton  # noqa: E402
from handdb.markers.fit import fit_markers  # noqa: E402
from handdb.markers.solve import track  # noqa: E402
from handdb.synthetic import synthesize_clip  # noqa: E402
from tests.support.paths import REAL_TOOLS  # noqa: E402
from tests.support.real_data import load_interhand, pseudo_clip  # noqa: E402

NOISE_MM = 1.0
HIDDEN_FRACTION = 6.0 / 21.0
MEAN_RUN_FRAMES = 6.0
SOLVER_FRAMES = 30
DHG = REPO / ".." / "shared" / "data" / "dhg-sample"
INTERHAND = REAL_TOOLS / "interhand" / "test_interhand2.6m_joint_3d.json"
#: Frames of each InterHand pseudo-clip.
INTERHAND_FRAMES = 60
#: Glove clips: this many frames (every :data:`GLOVE_STEP`-th, 33 Hz), starting at these
#: fractions of the recording.
GLOVE_CLIP_FRAMES = 100
GLOVE_STARTS = (0.0, 0.45, 0.9)
#: The glove is worn on the right hand (the recording's other markers are a right elbow
#: and shoulder).
GLOVE_HAND = "right"


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


def population(limit_weight: float | None = None) -> None:
    rows = []
    for seed in POPULATION_SEEDS:
        clip = synthesize_clip("random", POPULATION_FRAMES, seed=seed)
        rng = np.random.default_rng(seed)
        hidden = occlusion_runs(clip.xyz.shape[:2], HIDDEN_FRACTION, MEAN_RUN_FRAMES, rng)
        markers = clip.xyz + rng.normal(0.0, NOISE_MM, clip.xyz.shape)
        markers[hidden] = np.nan
        fit = fit_markers(markers, hand=clip.hand, units=clip.units,
                          calibration_limit_weight=limit_weight)
        err = errors(fit.joints, clip.xyz)
        rows.append((np.nanmean(fit.residual), err.mean(), err[hidden].mean()))
        print(f"population hand {seed}: visible-marker residual {rows[-1][0]:.2f} mm, MPJPE "
              f"{rows[-1][1]:.2f} mm (hidden joints {rows[-1][2]:.2f})")
    mean = np.mean(rows, axis=0)
    print(f"population mean: visible residual {mean[0]:.2f} mm, MPJPE {mean[1]:.2f} mm, "
          f"hidden {mean[2]:.2f} mm")


def dhg_sample(limit_weight: float | None = None) -> None:
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
    fit = fit_markers(partial, skeleton="dhg22", calibration_limit_weight=limit_weight)
    err = errors(fit.joints, markers)
    print(f"DHG sample on dhg22, 6 of 22 joints hidden a frame: visible residual "
          f"{np.nanmean(fit.residual):.1f} mm, MPJPE {err.mean():.1f} mm (hidden "
          f"{err[hidden].mean():.1f} mm)")
    markers = convert_points(markers, load_skeleton("dhg22"), load_skeleton("mediapipe21"))
    for hand in ("right", "left"):
        fit, rate = timed_fit(markers, hand, limit_weight)
        residual = fit.residual
        worst = fit.model.skeleton.joints[int(np.nanargmax(np.nanmean(residual, 0)))]
        print(f"DHG sample as a {hand} hand: {len(markers)} frames, marker-to-joint residual "
              f"mean {np.nanmean(residual):.1f} mm, median {np.nanmedian(residual):.1f} mm, "
              f"95th pct {np.nanpercentile(residual, 95):.1f} mm; worst joint {worst}; "
              f"{rate:.2f} frames/s")


def timed_fit(markers: np.ndarray, hand: str, limit_weight: float | None):
    """Fit ``markers`` (``(T, J, 3)`` mm, NaN hidden) with no lengths; the fit and frames/s."""
    start = time.perf_counter()
    fit = fit_markers(markers, hand=hand, units="mm", calibration_limit_weight=limit_weight)
    return fit, len(markers) / (time.perf_counter() - start)


def interhand(limit_weight: float | None = None) -> None:
    if not INTERHAND.is_file():
        print("InterHand2.6M: absent, skipped")
        return
    captures = load_interhand(INTERHAND)
    for occluded in (True, False):
        rows = []
        for index, capture in enumerate(captures):
            rng = np.random.default_rng(index)
            truth = pseudo_clip(capture.xyz[0], rng, INTERHAND_FRAMES)
            hidden = (occlusion_runs(truth.shape[:2], HIDDEN_FRACTION, MEAN_RUN_FRAMES, rng)
                      if occluded else np.zeros(truth.shape[:2], dtype=bool))
            markers = truth + rng.normal(0.0, NOISE_MM, truth.shape)
            markers[hidden] = np.nan
            fit, rate = timed_fit(markers, capture.hand, limit_weight)
            err = errors(fit.joints, truth)
            per_joint = err.mean(axis=0)
            worst = fit.model.skeleton.joints[int(np.argmax(per_joint))]
            rows.append((np.nanmean(fit.residual), err.mean(),
                         err[hidden].mean() if hidden.any() else np.nan))
            print(f"InterHand {capture.name} ({'~6 of 21 hidden' if occluded else 'all seen'}):"
                  f" visible residual {rows[-1][0]:.2f} mm, MPJPE {rows[-1][1]:.2f} mm "
                  f"(hidden {rows[-1][2]:.2f}), worst joint {worst} {per_joint.max():.1f} mm, "
                  f"{rate:.1f} frames/s")
        mean, median = np.mean(rows, axis=0), np.median(rows, axis=0)
        print(f"InterHand mean over {len(rows)} hands: visible {mean[0]:.2f}, MPJPE "
              f"{mean[1]:.2f}, hidden {mean[2]:.2f} mm (medians {median[0]:.2f}, "
              f"{median[1]:.2f}, {median[2]:.2f})")


def glove(limit_weight: float | None = None) -> None:
    if not GLOVE.is_file():
        print("Qualisys glove: absent, skipped")
        return
    from_glove = [joint for _, joint, *_ in GLOVE_MARKERS]
    skeleton = load_skeleton("mediapipe21")
    recording = glove_markers()[::GLOVE_STEP]
    residuals = []
    for share in GLOVE_STARTS:
        first = int(share * (len(recording) - GLOVE_CLIP_FRAMES))
        markers = np.full((GLOVE_CLIP_FRAMES, skeleton.n_joints, 3), np.nan)
        markers[:, [skeleton.index(j) for j in from_glove]] = recording[
            first:first + GLOVE_CLIP_FRAMES]
        fit, rate = timed_fit(markers, GLOVE_HAND, limit_weight)
        marked = [skeleton.index(j) for j in from_glove]
        seen = fit.residual[:, marked]
        per_frame = np.nanmean(seen[np.isfinite(seen).any(axis=1)], axis=1)
        per_joint = np.nanmean(seen, axis=0)
        worst = from_glove[int(np.nanargmax(per_joint))]
        residuals.append(seen)
        print(f"glove frames {first * GLOVE_STEP}-{(first + GLOVE_CLIP_FRAMES) * GLOVE_STEP} "
              f"(every {GLOVE_STEP}rd): visible residual mean {np.nanmean(fit.residual):.1f} "
              f"mm, per frame median {np.nanmedian(per_frame):.1f}, 95th pct "
              f"{np.nanpercentile(per_frame, 95):.1f}; worst joint {worst} "
              f"{np.nanmax(per_joint):.1f} mm; {rate:.1f} frames/s")
    pooled = np.concatenate(residuals)
    per_frame = np.nanmean(pooled[np.isfinite(pooled).any(axis=1)], axis=1)
    print(f"glove, {len(pooled)} frames: visible residual mean {np.nanmean(pooled):.1f} mm, "
          f"per frame median {np.nanmedian(per_frame):.1f}, 95th pct "
          f"{np.nanpercentile(per_frame, 95):.1f}")


SECTIONS = ("held_out", "population", "dhg", "interhand", "glove")


if __name__ == "__main__":
    frames = int(sys.argv[1]) if len(sys.argv) > 1 else 150
    chosen = sys.argv[2].split(",") if len(sys.argv) > 2 else SECTIONS
    weight = float(sys.argv[3]) if len(sys.argv) > 3 else None
    runs = {"held_out": lambda _: held_out(frames), "population": population,
            "dhg": dhg_sample, "interhand": interhand, "glove": glove}
    for section in chosen:
        runs[section](weight)
