"""Gap filling: accuracy of every method under the issue's masks, and the default's speed.

Accuracy (RMSE over hidden points, pixels; the DHG capture is read as 1 px = 1 mm):

* synthetic ``rapid`` clips of 400 frames (orthographic, mediapipe21): Table 4.2's mask on
  the four 100-frame clips each makes, 40 random interior gaps of 1-60 frames, and the
  points the hand's own mesh hides from the camera;
* the real DHG capture (``../shared/data/dhg-sample``, 95 frames, projected by dropping z):
  Table 4.2's mask cut to 95 frames, and 10 random gaps (40 per 400 frames).

Speed: frames of the clip filled per CPU-second (and per wall-clock second) by the default
on 400-, 4000- and 20000-frame clips (synthetic clips joined end to end) with 5 % of the
points hidden in random gaps of 1-60 frames; the best of several runs, as the machine is
shared (the load average is printed beside); then every offline method on 4000 frames
with 40 random gaps per 400 frames.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_gapfill.py [--seeds N]
[--frames N] [--repeats N] [--speed-only]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.gapfill import DEFAULT_METHOD, METHODS, THESIS, fill_gaps, method_names  # noqa: E402
from handdb.gapfill.evaluate import (  # noqa: E402
    OCCLUSION_MASK,
    RANDOM_MASK,
    THESIS_MASK,
    evaluate_clip,
    overall_rmse,
)
from handdb.gapfill.masks import RANDOM_GAP_FRAMES, random_gaps_mask  # noqa: E402
from handdb.hand.skeletons import load_skeleton  # noqa: E402
from handdb.synthetic.clips import synthesize_clip  # noqa: E402

DHG = REPO / ".." / "shared" / "data" / "dhg-sample"
MM_PER_M = 1000.0
MASKS = (THESIS_MASK, RANDOM_MASK)
#: Clip lengths (frames) the default's speed is measured on.
SPEED_FRAMES = (400, 4000, 20000)
SYNTHETIC_MASKS = (*MASKS, OCCLUSION_MASK)


def pooled(evaluations, mask, method):
    squared = np.concatenate([e.errors[(mask, method)][e.hidden[mask]] ** 2
                              for e in evaluations])
    return float(np.sqrt(np.nanmean(squared)))


def print_accuracy(title, evaluations, masks):
    print(f"\n{title}")
    print(f"{'method':18s} {'family':8s} " + " ".join(f"{m:>17s}" for m in masks))
    for method in METHODS:
        cells = " ".join(f"{pooled(evaluations, m, method):17.2f}" for m in masks)
        print(f"{method:18s} {METHODS[method].family:8s} {cells}")
    for mask in masks:
        best = min(method_names(THESIS), key=lambda m: pooled(evaluations, mask, m))
        ratio = pooled(evaluations, mask, best) / pooled(evaluations, mask, "auto")
        target = " (target >= 5)" if mask in MASKS else ""
        print(f"{mask}: best thesis method {best} / auto = {ratio:.2f}{target}")


def accuracy_synthetic(seeds, n_frames):
    skeleton = load_skeleton("mediapipe21")
    clips = [synthesize_clip("rapid", n_frames, seed=s) for s in range(seeds)]
    evaluations = [
        evaluate_clip(f"rapid-{s}", clip.uv, skeleton, masks=SYNTHETIC_MASKS, xyz=clip.xyz, seed=s)
        for s, clip in enumerate(clips)
    ]
    print_accuracy(f"synthetic rapid, {seeds} clips of {n_frames} frames (pixels)", evaluations,
                   SYNTHETIC_MASKS)
    hidden = np.mean([e.hidden[OCCLUSION_MASK].mean() for e in evaluations])
    print(f"  occlusion hides {hidden:.1%} of the points")
    for e in evaluations:
        rmse = overall_rmse(e)
        clip = e.table.column("clip_id")[0].as_py()
        print(f"  {clip}: " + ", ".join(
            f"{mask} auto {rmse[(mask, 'auto')]:.2f} / previous {rmse[(mask, 'previous')]:.2f}"
            for mask in MASKS))


def accuracy_dhg():
    path = DHG / "skeletons_world.txt"
    if not path.is_file():
        print(f"\nDHG sample not found at {DHG}: skipped")
        return
    skeleton = load_skeleton("dhg22")
    uv = np.loadtxt(path).reshape(-1, skeleton.n_joints, 3)[..., :2] * MM_PER_M
    evaluations = [evaluate_clip("dhg", uv, skeleton, masks=MASKS, seed=s) for s in range(4)]
    print_accuracy("real DHG capture, 95 frames, mm (random gaps: 4 seeds)", evaluations, MASKS)


def robustness():
    print("\nother skeletons, a left hand, a pinhole camera (rapid, seed 1, 40 random gaps)")
    for name in ("mediapipe21", "thesis21", "dhg22"):
        skeleton = load_skeleton(name)
        for hand, camera in (("left", "orthographic"), ("right", "pinhole")):
            uv = synthesize_clip("rapid", 400, seed=1, hand=hand, camera=camera,
                                 skeleton=name).uv
            hidden = random_gaps_mask(400, skeleton.n_joints, seed=1)
            rmse = {}
            for method in ("auto", "previous"):
                filled = fill_gaps(uv, ~hidden, skeleton, method).uv
                rmse[method] = np.sqrt(np.mean(np.sum((filled - uv) ** 2, axis=-1)[hidden]))
            print(f"  {name:12s} {hand:5s} {camera:12s} auto {rmse['auto']:6.2f}  previous "
                  f"{rmse['previous']:6.2f}  ratio {rmse['previous'] / rmse['auto']:5.1f}")


def _timed(uv, observed, skeleton, method, repeats, **params):
    """Best wall and CPU seconds of ``repeats`` runs of :func:`fill_gaps`."""
    wall = cpu = np.inf
    for _ in range(repeats):
        start_wall, start_cpu = time.perf_counter(), time.process_time()
        fill_gaps(uv, observed, skeleton, method, **params)
        wall = min(wall, time.perf_counter() - start_wall)
        cpu = min(cpu, time.process_time() - start_cpu)
    return wall, cpu


def speed_clip(n_frames, share, skeleton):
    """Rapid clips joined to ``n_frames``, ``share`` of the points hidden in 1-60-frame gaps."""
    n_clips = -(-n_frames // 400)
    uv = np.concatenate([synthesize_clip("rapid", 400, seed=s).uv for s in range(n_clips)])
    mean_gap = np.mean(RANDOM_GAP_FRAMES)
    n_gaps = max(1, round(share * n_frames * skeleton.n_joints / mean_gap))
    return uv[:n_frames], random_gaps_mask(n_frames, skeleton.n_joints, n_gaps=n_gaps, seed=0)


def speed(repeats):
    skeleton = load_skeleton("mediapipe21")
    print(f"\nspeed of the default, {DEFAULT_METHOD!r}: 5 % of the points hidden in gaps of 1-60 "
          f"frames; best of {repeats} runs, more on shorter clips (load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print(f"  {'frames':>6s} {'hidden':>6s} {'CPU ms':>8s} {'frames per CPU-second':>22s} "
          f"{'wall ms':>8s} {'frames per wall-second':>23s}")
    for n_frames in SPEED_FRAMES:
        uv, hidden = speed_clip(n_frames, 0.05, skeleton)
        runs = max(repeats, repeats * SPEED_FRAMES[-1] // n_frames)
        wall, cpu = _timed(uv, ~hidden, skeleton, DEFAULT_METHOD, runs)
        print(f"  {n_frames:6d} {hidden.mean():6.1%} {cpu * 1e3:8.1f} {n_frames / cpu:22,.0f} "
              f"{wall * 1e3:8.1f} {n_frames / wall:23,.0f}")
    uv, hidden = speed_clip(4000, 0.14, skeleton)
    print(f"\nevery method on 4000 frames, {hidden.mean():.1%} hidden (40 gaps per 400 frames)")
    print(f"  {'method':26s} {'frames per CPU-second':>22s} {'frames per wall-second':>23s}")
    runs = [(method, {}) for method in ("linear", "pchip", "rigid", "lowrank", "auto")]
    runs += [("auto", {"long_gaps": rule}) for rule in ("chain", "regression", "lowrank")]
    for method, params in runs:
        wall, cpu = _timed(uv, ~hidden, skeleton, method, repeats, **params)
        label = method + "".join(f", {key}={value}" for key, value in params.items())
        print(f"  {label:26s} {4000 / cpu:22,.0f} {4000 / wall:23,.0f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=4, help="synthetic clips")
    parser.add_argument("--frames", type=int, default=400, help="frames per synthetic clip")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per speed figure")
    parser.add_argument("--speed-only", action="store_true", help="skip the accuracy tables")
    args = parser.parse_args()
    if not args.speed_only:
        accuracy_synthetic(args.seeds, args.frames)
        accuracy_dhg()
        robustness()
    speed(args.repeats)


if __name__ == "__main__":
    main()
