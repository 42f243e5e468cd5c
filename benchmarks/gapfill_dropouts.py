"""How well ``auto`` fills what detectors drop: whole empty frames and joints never found.

On the clips of :mod:`benchmarks.gapfill_datasets` (real first: the DHG sample, the
development set, projected orthographically and by a pinhole; MediaPipe's own landmarks
of two hands, held out; then synthetic hands), two conditions:

* ``empty L``: interior runs of ``L`` frames with every point hidden (:data:`RUN_LENGTHS`,
  :data:`RUNS_PER_CLIP` runs per clip at random, apart), scored on the hidden points;
* ``never J``: joint ``J`` hidden in every frame (placed by the hand model), scored on
  every frame, and with :data:`RUNS_PER_CLIP` empty runs of 4 frames as well.

Errors are RMSE in pixels and as a share of the hand's size in the image (the median
over frames of the larger side of its box). No constant of the method was chosen on
these figures.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/gapfill_dropouts.py
[--synthetic-seeds N]``; the figures are in ``RESULTS-gapfill.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.gapfill_datasets import (  # noqa: E402
    Case,
    dhg_cases,
    mediapipe_cases,
    synthetic_cases,
)
from handdb.gapfill import fill_gaps  # noqa: E402

#: Lengths of the empty runs, frames (the longest ``auto`` bridges is 8).
RUN_LENGTHS = (1, 2, 4, 8)
#: Empty runs per clip, and the fewest observed frames between two of them.
RUNS_PER_CLIP = 4
MIN_APART = 3
#: Joints hidden in every frame, where the clip's skeleton has them.
NEVER_FOUND = ("thumb_tip", "index_tip", "little_tip", "little_dip")
#: Length of the empty runs added to a never-found joint, frames.
RUN_WITH_NEVER = 4
SEED = 11


def empty_runs(n_frames: int, length: int, rng: np.random.Generator) -> np.ndarray:
    """``(T,) bool``: :data:`RUNS_PER_CLIP` interior runs of ``length`` frames, apart."""
    empty = np.zeros(n_frames, dtype=bool)
    placed = 0
    while placed < RUNS_PER_CLIP:
        start = int(rng.integers(1, n_frames - length - 1))
        if not empty[max(start - MIN_APART, 0):start + length + MIN_APART].any():
            empty[start:start + length] = True
            placed += 1
    return empty


def hand_size_px(uv: np.ndarray) -> float:
    """Median over frames of the larger side of the hand's box, pixels."""
    return float(np.nanmedian(np.nanmax(np.nanmax(uv, axis=1) - np.nanmin(uv, axis=1),
                                        axis=-1)))


def rmse(case: Case, hidden: np.ndarray, method: str) -> float:
    """RMSE of ``method`` on the ``hidden`` ``(T, J)`` points that exist, pixels."""
    exists = np.isfinite(case.uv).all(axis=-1)
    result = fill_gaps(case.uv, exists & ~hidden, case.skeleton, method)
    scored = hidden & exists
    return float(np.sqrt(np.nanmean(np.sum((result.uv[scored] - case.uv[scored]) ** 2,
                                           axis=-1))))


def rows(case: Case, rng: np.random.Generator) -> list[tuple[str, float]]:
    """``(condition, RMSE of auto)`` for one clip, pixels."""
    n_frames, n_joints = case.uv.shape[:2]
    out = []
    for length in RUN_LENGTHS:
        hidden = np.repeat(empty_runs(n_frames, length, rng)[:, None], n_joints, axis=1)
        out.append((f"empty {length}", rmse(case, hidden, "auto")))
    for joint in (j for j in NEVER_FOUND if j in case.skeleton.joints):
        never = np.zeros((n_frames, n_joints), dtype=bool)
        never[:, case.skeleton.index(joint)] = True
        out.append((f"never {joint}", rmse(case, never, "auto")))
        with_runs = never | empty_runs(n_frames, RUN_WITH_NEVER, rng)[:, None]
        out.append((f"never {joint} + empty {RUN_WITH_NEVER}",
                    rmse(case, with_runs, "auto")))
    return out


def report(cases: list[Case]) -> str:
    """The table: per dataset and projection, each condition's mean RMSE over its clips."""
    rng = np.random.default_rng(SEED)
    pooled: dict[tuple[str, str, str], list[tuple[float, float]]] = {}
    for case in cases:
        size = hand_size_px(case.uv)
        for condition, error in rows(case, rng):
            key = (f"{case.dataset}{'' if case.held_out else ' (dev)'}", case.projection,
                   condition)
            pooled.setdefault(key, []).append((error, size))
    lines = ["| data | projection | condition | RMSE px | RMSE % of hand |",
             "|---|---|---|---|---|"]
    for (data, projection, condition), values in pooled.items():
        error, size = np.asarray(values).T
        lines.append(f"| {data} | {projection} | {condition} | {np.mean(error):.1f} | "
                     f"{100 * np.mean(error / size):.1f} |")
    return "\n".join(lines)


def main() -> None:
    """Print the table, real data first."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--synthetic-seeds", type=int, default=2)
    args = parser.parse_args()
    cases = [*dhg_cases(), *mediapipe_cases(),
             *synthetic_cases(range(args.synthetic_seeds), n_frames=200,
                              motions=("rapid", "wave"))]
    sys.stdout.write(report(cases) + "\n")


if __name__ == "__main__":
    main()
