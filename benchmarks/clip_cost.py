"""A build's cost per short clip, stage by stage (issue 16: fixed cost per clip <= 50 ms).

Writes an inbox of ``--clips`` synthetic clips of ``--frames`` frames the way
``benchmarks/run.py`` does, runs every stage on each clip by calling
``handdb.build.stages`` directly (``run.py``'s stage timing, on one BLAS thread), once
on a warm-up inbox so compiled kernels and imports are loaded, then prints each stage's
CPU and wall milliseconds per clip, and the I/O floor of the same inbox (``run.py``'s:
pyarrow reads its CSV files and writes their rows as Parquet) with the stages' ratio to
it. At 300 frames a clip's cost is almost all fixed: it does not scale with frames. CPU
time is the figure to compare on a shared machine.

Run: ``.venv/bin/python benchmarks/clip_cost.py [--clips 30] [--frames 300]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from run import POOL_SIZE, io_floor, load_average, stage_timings, write_inbox  # noqa: E402

#: Clips and frames per clip of the measured inbox (``run.py``'s fixed-cost builds).
CLIPS, FRAMES = 30, 300


def main() -> None:
    """Measure and print the per-clip cost of every stage."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=CLIPS)
    parser.add_argument("--frames", type=int, default=FRAMES)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        write_inbox(folder / "warm-up", POOL_SIZE, args.frames)
        write_inbox(folder / "inbox", args.clips, args.frames)
        stage_timings(folder / "warm-up", folder / "warm-up-db")
        load = load_average()
        timings = stage_timings(folder / "inbox", folder / "db")
        floor = io_floor(folder / "inbox", folder / "floor")
    print(f"{args.clips} clips x {args.frames} frames, load {load:.1f} -> {load_average():.1f}")
    print(f"{'stage':14s} {'CPU ms/clip':>12s} {'wall ms/clip':>13s}")
    for stage, timing in timings.items():
        print(f"{stage:14s} {1000 * timing.cpu / args.clips:12.1f} "
              f"{1000 * timing.wall / args.clips:13.1f}")
    cpu = sum(timing.cpu for timing in timings.values())
    wall = sum(timing.wall for timing in timings.values())
    print(f"{'all stages':14s} {1000 * cpu / args.clips:12.1f} {1000 * wall / args.clips:13.1f}")
    print(f"{'I/O floor':14s} {1000 * floor.cpu / args.clips:12.1f} "
          f"{1000 * floor.wall / args.clips:13.1f}")
    print(f"{'stages / floor':14s} {cpu / floor.cpu:12.1f} {wall / floor.wall:13.1f}")


if __name__ == "__main__":
    main()
