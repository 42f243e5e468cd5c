"""Lifting across a detector's dropped frames: do the other frames keep their answer?

Prints, per set (the synthetic population, the real DHG capture in its own view and in
random views, and with ``--interhand`` InterHand2.6M pseudo-clips in random views), camera
and pixel noise, the mean root-relative error (mm) of the default lifting on the frames
that stay observed, lifted from the full clip and from the clip with runs of whole frames
emptied, and the mean and largest change of a kept joint between the two. The emptied
runs are :data:`RUNS` runs of 1 to :data:`LONGEST_RUN` frames at random places (seeded
per case), as a detector drops them.

Run: ``.venv/bin/python benchmarks/empty_frames.py [--interhand]``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from benchmarks.real_captures import (  # noqa: E402
    INTERHAND,
    Case,
    CaseSource,
    native_cases,
    synthetic_cases,
    view_cases,
)
from handdb.lifting import lift  # noqa: E402
from tests.support import real_data  # noqa: E402
from tests.support.paths import DHG_SAMPLE  # noqa: E402

#: Runs of empty frames per clip, and the longest, frames.
RUNS, LONGEST_RUN = 3, 20
#: Seeds of the tracks' pixel noise and (with the clip's index) of the emptied runs.
NOISE_SEED, EMPTY_SEED = 7, 11
#: Synthetic seeds and motions measured.
SEEDS, MOTIONS = (0, 1, 2), ("wave", "rapid", "clench")
#: Fixed random views of the real captures.
VIEWS = 4
#: Pixel noise levels of the tracks.
NOISE_PX = (0.0, 1.0)


def empty_runs(n_frames: int, rng: np.random.Generator) -> np.ndarray:
    """``(T,) bool``: :data:`RUNS` random runs of 1 to :data:`LONGEST_RUN` frames."""
    empty = np.zeros(n_frames, dtype=bool)
    for length in rng.integers(1, LONGEST_RUN + 1, size=RUNS):
        start = int(rng.integers(0, n_frames - length + 1))
        empty[start:start + length] = True
    return empty


def root_relative_error(xyz: np.ndarray, truth: np.ndarray) -> float:
    """Mean distance of root-relative joints, ``(T, J, 3)`` inputs, mm."""
    return float(np.nanmean(np.linalg.norm((xyz - xyz[:, :1]) - (truth - truth[:, :1]),
                                           axis=-1)))


def compare(case: Case, empty: np.ndarray) -> tuple[float, float, float, float]:
    """Errors on the kept frames lifted full and with ``empty`` emptied, and their change.

    Returns the two mean root-relative errors and the mean and largest change of a kept
    joint between the two lifts, mm.
    """
    full = lift(case.uv, case.skeleton, case.lengths, case.camera, hand=case.hand).xyz
    uv = case.uv.copy()
    uv[empty] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        part = lift(uv, case.skeleton, case.lengths, case.camera, hand=case.hand).xyz
    keep = ~empty
    change = np.linalg.norm((part - part[:, :1]) - (full - full[:, :1]), axis=-1)[keep]
    return (root_relative_error(full[keep], case.truth[keep]),
            root_relative_error(part[keep], case.truth[keep]), float(np.nanmean(change)),
            float(np.nanmax(change)))


def sets(interhand: bool) -> Iterator[tuple[str, CaseSource]]:
    """Name and case source of every set measured."""
    yield "synthetic", synthetic_cases(SEEDS, MOTIONS)
    if DHG_SAMPLE.is_file():
        dhg = real_data.load_dhg(DHG_SAMPLE)
        yield "dhg (own view)", native_cases(dhg)
        yield f"dhg ({VIEWS} random views)", view_cases([dhg], VIEWS, False)
    if interhand and INTERHAND.is_file():
        yield "interhand pseudo-clips", view_cases(real_data.load_interhand(INTERHAND), VIEWS,
                                                   True)


def main(argv: list[str] | None = None) -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--interhand", action="store_true", help="also the held-out set")
    args = parser.parse_args(argv)
    print("| set | camera | noise px | clips | full mm | emptied mm | mean change mm |"
          " largest change mm |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for name, source in sets(args.interhand):
        for camera in ("orthographic", "pinhole"):
            for noise in NOISE_PX:
                rows = []
                cases = source(camera, noise, np.random.default_rng(NOISE_SEED))
                for index, case in enumerate(cases):
                    empty = empty_runs(len(case.uv), np.random.default_rng([EMPTY_SEED, index]))
                    rows.append(compare(case, empty))
                full, part, change, largest = np.mean(rows, axis=0)
                print(f"| {name} | {camera} | {noise:g} | {len(rows)} | {full:.2f} | "
                      f"{part:.2f} | {change:.2f} | {np.max(rows, axis=0)[3]:.1f} |",
                      flush=True)


if __name__ == "__main__":
    main()
