"""Pinhole lifting: how much of the error is the root's depth (issue 14).

Prints, per dataset of :mod:`real_captures` (same cases, views, seeds and bone lengths,
pinhole camera only, one draw of the real captures' pixel noise) and pixel noise level:

- the default lifter's mean root-relative |dZ| with the root depth it estimates
  (:func:`handdb.lifting.pinhole.estimate_root_depth`) and with the true root depth
  substituted; the estimate's relative error (estimate / truth - 1 per frame: mean, mean
  absolute, median absolute) and the Pearson correlation over cases of a case's mean
  absolute root error with its |dZ|;
- with ``--factors``, the mean |dZ| with the true root depth times each of ``FACTORS``.

The root depth is substituted by patching the name ``estimate_root_depth`` inside
:mod:`handdb.lifting.kinematic` for the duration of one lift; nothing else changes. These
are the first two tables of ``benchmarks/RESULTS-root-depth.md``.

Run: ``.venv/bin/python benchmarks/root_depth.py [--quick] [--factors]``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from unittest import mock

import numpy as np

BENCHMARKS = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCHMARKS))

import real_captures as rc  # noqa: E402

from handdb.lifting import kinematic, lift, pinhole  # noqa: E402
from tests.support import real_data  # noqa: E402

#: Pixel noise levels.
NOISE_PX = (0.0, 1.0)

#: Multiples of the true root depth of the sensitivity table.
FACTORS = (0.98, 0.99, 0.995, 1.0, 1.005, 1.01, 1.02, 1.05, 1.1)

#: Root-depth sources: ``None`` is the library's estimate, a float the true depth times it.
RootSource = float | None


def _lift_case(case: rc.Case, source: RootSource) -> tuple[np.ndarray, np.ndarray]:
    """Lift one pinhole case; the pose ``(T, J, 3)`` mm and the root depth used ``(T,)`` mm."""
    used: list[np.ndarray] = []
    truth_root = case.truth[:, case.skeleton.root, 2]

    def root_depth(*args: object) -> np.ndarray:
        depth = (pinhole.estimate_root_depth(*args) if source is None
                 else truth_root * source)
        used.append(depth)
        return depth

    with mock.patch.object(kinematic, "estimate_root_depth", root_depth):
        xyz = lift(case.uv, case.skeleton, case.lengths, case.camera, method="kinematic",
                   hand=case.hand).xyz
    return xyz, used[-1]


def measure(cases: rc.CaseSource, noise: float, source: RootSource) -> dict[str, float]:
    """Pooled |dZ| mm and root-error statistics of one dataset, noise level and source."""
    rng = np.random.default_rng([rc.NOISE_SEED, int(round(10 * noise))])
    pooled: real_data.Errors | None = None
    relative, case_dz, case_root = [], [], []
    for case in cases("pinhole", noise, rng):
        xyz, depth = _lift_case(case, source)
        error = depth / case.truth[:, case.skeleton.root, 2] - 1.0
        relative.append(error)
        one = real_data.Errors(case.skeleton)
        one.add(case.truth, xyz)
        case_dz.append(one.summary()["all"]["dz"])
        case_root.append(float(np.nanmean(np.abs(error))))
        if pooled is None:
            pooled = real_data.Errors(case.skeleton)
        pooled.add(case.truth, xyz)
    assert pooled is not None, "a dataset without cases"
    errors = np.concatenate(relative)
    with np.errstate(invalid="ignore"):
        correlation = (float(np.corrcoef(case_root, case_dz)[0, 1]) if len(case_dz) > 2
                       else float("nan"))
    return {"dz": pooled.summary()["all"]["dz"], "mean": float(np.nanmean(errors)),
            "mean_abs": float(np.nanmean(np.abs(errors))),
            "median_abs": float(np.nanmedian(np.abs(errors))),
            "corr": correlation, "cases": len(case_dz)}


def datasets(plan: dict) -> list[tuple[str, rc.CaseSource]]:
    """``(name, cases)`` of every dataset present."""
    out: list[tuple[str, rc.CaseSource]] = []
    if rc.DHG_SAMPLE.is_file():
        dhg = real_data.load_dhg(rc.DHG_SAMPLE)
        out += [("DHG own view", rc.native_cases(dhg)),
                (f"DHG {plan['views']} random views", rc.view_cases([dhg], plan["views"], False))]
    if rc.INTERHAND.is_file():
        hands = real_data.load_interhand(rc.INTERHAND)
        out += [("InterHand single frames", rc.view_cases(hands, plan["views"], False)),
                ("InterHand pseudo-clips", rc.view_cases(hands, plan["views"], True))]
    out.append((f"synthetic population ({len(plan['seeds']) * len(plan['motions'])} clips)",
                rc.synthetic_cases(plan["seeds"], plan["motions"])))
    return out


def error_table(sets: list[tuple[str, rc.CaseSource]]) -> list[str]:
    """The "where the error is" table."""
    lines = ["| dataset | noise px | dZ current | dZ true root | root error mean | mean abs "
             "| median abs | corr over cases |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, cases in sets:
        for noise in NOISE_PX:
            current, true = measure(cases, noise, None), measure(cases, noise, 1.0)
            corr = (f"{current['corr']:+.2f}" if current["cases"] > 2
                    else f"({current['cases']} case{'s' * (current['cases'] > 1)})")
            lines.append(f"| {name} | {noise:g} | {current['dz']:.1f} | {true['dz']:.1f} | "
                         f"{100 * current['mean']:+.1f} % | {100 * current['mean_abs']:.1f} % | "
                         f"{100 * current['median_abs']:.1f} % | {corr} |")
    return lines


def factor_table(sets: list[tuple[str, rc.CaseSource]]) -> list[str]:
    """Mean |dZ| mm with the true root depth times each factor, one cell per noise level."""
    lines = ["| dataset | " + " | ".join(f"x{f:g}" for f in FACTORS) + " |",
             "|---|" + "---:|" * len(FACTORS)]
    for name, cases in sets:
        cells = [" / ".join(f"{measure(cases, noise, f)['dz']:.1f}" for noise in NOISE_PX)
                 for f in FACTORS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def main(argv: list[str] | None = None) -> None:
    """Print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="two views, one synthetic clip")
    parser.add_argument("--factors", action="store_true",
                        help="also the true root depth times each factor")
    args = parser.parse_args(argv)
    sets = datasets(rc.QUICK if args.quick else rc.FULL)
    tables: list[Callable[[list[tuple[str, rc.CaseSource]]], list[str]]] = [error_table]
    if args.factors:
        tables.append(factor_table)
    for table in tables:
        sys.stdout.write("\n".join(table(sets)) + "\n\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
