"""Throughput of depth reconstruction (issue 4): frames per second of every lifting method.

Clips of rapid gestures (mediapipe21, 21 joints), orthographic and pinhole, at several
lengths; the best of a few runs of :func:`handdb.lifting.lift` per setting. Then the
default lifting many clips at once on one thread and on one per core, as the build's
worker threads do. The machine's
load average is printed too, since the figures scale with the share of a core the
process gets.

Run: ``.venv/bin/python benchmarks/bench_lifting.py``.
"""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.clip import Camera  # noqa: E402
from handdb.hand.skeletons import bone_length_array, load_skeleton  # noqa: E402
from handdb.lifting import available_methods, lift  # noqa: E402
from handdb.synthetic.clips import synthesize_clip  # noqa: E402

LENGTHS = (400, 10_000, 100_000)

#: Longest clip timed for the slow settings: the least-squares refinement, and the
#: model fit (a bounded least-squares problem per frame).
SLOW_MAX_FRAMES = {"kinematic-refined": 400, "model-fit": 400}
REPEATS = 3


def too_slow(method: str, n_frames: int) -> bool:
    """Whether a setting is left untimed (see :data:`SLOW_MAX_FRAMES`)."""
    return n_frames > SLOW_MAX_FRAMES.get(method, n_frames)


def frames_per_second(uv, skeleton, lengths, camera, method) -> float:
    """Best of :data:`REPEATS` runs, frames per second."""
    best = float("inf")
    for _ in range(REPEATS):
        start = time.perf_counter()
        lift(uv, skeleton, lengths, camera, method=method)
        best = min(best, time.perf_counter() - start)
    return len(uv) / best


def throughput_table(clip_lengths: tuple[int, ...] = LENGTHS) -> list[str]:
    """Frames per second of every method and camera, as lines of a markdown table."""
    lines = [f"Load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; frames per "
             "second, best of 3, by clip length:", "",
             "| camera | method | " + " | ".join(f"{n} frames" for n in clip_lengths) + " |",
             "|---|---|" + "---:|" * len(clip_lengths)]
    for camera_model in ("orthographic", "pinhole"):
        clip = synthesize_clip("rapid", 400, camera=camera_model, seed=0)
        skeleton = load_skeleton(clip.skeleton)
        lengths = bone_length_array(skeleton, clip.bone_lengths)
        camera = Camera(**clip.camera) if camera_model == "pinhole" else Camera()
        for method in available_methods():
            rates = []
            for n_frames in clip_lengths:
                if too_slow(method, n_frames):
                    rates.append(float("nan"))
                    continue
                uv = np.tile(clip.uv, (n_frames // len(clip.uv), 1, 1))
                rates.append(frames_per_second(uv, skeleton, lengths, camera, method))
            lines.append(f"| {camera_model} | {method} | "
                         + " | ".join("" if np.isnan(r) else f"{r:,.0f}" for r in rates)
                         + " |")
    return lines


def parallel_throughput(n_frames: int = 10_000, clips_per_worker: int = 4) -> list[str]:
    """Frames per second of the default lifting many clips at once, as the pipeline does.

    The build lifts clips concurrently on its worker threads; the compiled kernels release
    the GIL, so the machine's cores share the work. Clips of rapid gestures (orthographic,
    seeds 0-3) are lifted by 1 thread and by one per core, wall-clock, best of
    :data:`REPEATS`.
    """
    batch = []
    for seed in range(4):
        clip = synthesize_clip("rapid", 400, seed=seed)
        skeleton = load_skeleton(clip.skeleton)
        lengths = bone_length_array(skeleton, clip.bone_lengths)
        batch.append((np.tile(clip.uv, (n_frames // len(clip.uv), 1, 1)), skeleton, lengths))
    lines = [f"Default method, orthographic, {n_frames}-frame clips lifted concurrently "
             f"(load average {os.getloadavg()[0]:.1f}):", "",
             "| threads | frames per second |", "|---:|---:|"]
    for workers in sorted({1, os.cpu_count() or 1}):
        clips = [batch[i % len(batch)] for i in range(workers * clips_per_worker)]
        best = float("inf")
        for _ in range(REPEATS):
            start = time.perf_counter()
            with ThreadPoolExecutor(workers) as pool:
                list(pool.map(lambda c: lift(c[0], c[1], c[2], Camera()), clips))
            best = min(best, time.perf_counter() - start)
        lines.append(f"| {workers} | {len(clips) * n_frames / best:,.0f} |")
    return lines


def main() -> None:
    print("\n".join(throughput_table()))
    print()
    print("\n".join(parallel_throughput()))


if __name__ == "__main__":
    main()
