"""As a detector gives it, decomposed: the same pipeline with one factor at a time made exact.

Issue 14's detector-like input (``benchmarks/detector_pipeline.py``: pinhole, 1 px noise,
short dropouts, five bone lengths known, the X-ray Table 1 as the joint ratios) runs through
the build's own stages; then each factor of its error is replaced by its oracle, alone and
in combinations, and the default lifting's root-relative MPJPE and PA-MPJPE are printed per
dataset, so the error decomposes. The oracles:

- ``lengths``: every bone given its median true length (the sidecar gives all of them);
- ``root depth``: the lifting's root depth per frame replaced by the truth's (the pinhole
  lifting's :func:`handdb.lifting.pinhole.estimate_root_depth` is swapped for the truth
  while the clip is lifted, so the signs are chosen knowing it);
- ``signs``: after lifting, every joint is walked again along its ray from the lifted root
  (:func:`handdb.lifting.pinhole.walk_rays`) taking, of the two points at its bone's length
  from its parent, the one on the true side: the signs exact, the lengths and rays those
  the lifting had;
- ``no noise``: the truth's exact projection instead of the noisy points;
- ``no dropouts``: every point kept with full confidence.

With every oracle at once the result is the truth made length-consistent along its own
rays: on a tracker's output (DHG, whose per-frame bone lengths vary) that is the floor no
lifting with one length per bone can go below; on rigid data it is 0.

Datasets are those of ``benchmarks/detector_pipeline.py`` (DHG in its own view and in
random views, InterHand2.6M held out and reported only, the synthetic population).

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/detector_oracles.py [--quick]``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pyarrow as pa

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from benchmarks.detector_pipeline import (  # noqa: E402
    FULL,
    KNOWN_BONES,
    NOISE_SEED,
    PROVENANCE,
    QUICK,
    Case,
    as_clip,
    build_ratios,
    datasets,
    detector_tracks,
)
from handdb.build.options import BuildOptions  # noqa: E402
from handdb.build.stages import ClipResult, fill, resolve_bone_lengths  # noqa: E402
from handdb.clip import finite_points  # noqa: E402
from handdb.denoise import denoise  # noqa: E402
from handdb.lifting import kinematic, lift  # noqa: E402
from handdb.lifting.geometry import intrinsics  # noqa: E402
from handdb.lifting.pinhole import camera_rays, walk_rays  # noqa: E402
from handdb.synthetic.projection import project_pinhole  # noqa: E402
from tests.support import real_data  # noqa: E402

#: The factors, each made exact by its oracle.
FACTORS = ("lengths", "root depth", "signs", "no noise", "no dropouts")

#: The oracle sets scored: none, each alone, every one but each, and the pairs that matter.
ORACLE_SETS: tuple[frozenset[str], ...] = (
    frozenset(),
    *(frozenset({f}) for f in FACTORS),
    frozenset({"lengths", "root depth"}),
    frozenset({"lengths", "signs"}),
    frozenset({"root depth", "signs"}),
    frozenset({"lengths", "root depth", "signs"}),
    *(frozenset(FACTORS) - {f} for f in FACTORS),
    frozenset(FACTORS),
)


def label(oracles: frozenset[str]) -> str:
    """Row label of an oracle set, its factors in :data:`FACTORS` order."""
    return " + ".join(f for f in FACTORS if f in oracles) or "none (as a detector gives it)"


@contextmanager
def true_root_depth(truth: np.ndarray, root: int) -> Iterator[None]:
    """While open, the pinhole lifting takes the truth's root depth ``(T,)`` mm."""
    estimate = kinematic.estimate_root_depth
    kinematic.estimate_root_depth = lambda *_: truth[:, root, 2].copy()
    try:
        yield
    finally:
        kinematic.estimate_root_depth = estimate


def signs_oracle(xyz: np.ndarray, uv: np.ndarray, case: Case,
                 lengths: np.ndarray) -> np.ndarray:
    """The lifted joints walked again along their rays with every depth sign the truth's.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64``, mm: the lifting's result, whose root depth is kept.
    uv
        ``(T, J, 2) float64``, pixels: the points the lifting was given (denoised as it
        denoises them).
    case
        The clip's truth and camera.
    lengths
        ``(J,) float64``, mm: the lengths the lifting was given.
    """
    skeleton = case.skeleton
    rays = camera_rays(denoise(uv, ~finite_points(uv))[0], case.camera)
    parents = np.where(skeleton.parents < 0, skeleton.root, skeleton.parents)
    true_dz = case.truth[..., 2] - case.truth[:, parents, 2]
    return walk_rays(rays, xyz[:, skeleton.root, 2], skeleton, lengths, true_dz)[0]


def exact_points(case: Case) -> np.ndarray:
    """``(T, J, 2)`` pixels: the truth's projection through the clip's camera, no noise."""
    fx, fy, cx, cy = intrinsics(case.camera)
    return project_pinhole(case.truth, fx, fy, cx, cy)


def lift_with(case: Case, oracles: frozenset[str], ratios: pa.Table,
              rng: np.random.Generator) -> np.ndarray:
    """The default pipeline's ``(T, J, 3)`` mm result with the given oracles."""
    uv = exact_points(case) if "no noise" in oracles else case.uv
    tracks, confidence = ((uv, np.ones(uv.shape[:2])) if "no dropouts" in oracles
                          else detector_tracks(uv, rng))
    true_lengths = real_data.median_bone_lengths(case.truth, case.skeleton)
    every = {case.skeleton.joints[j]: float(true_lengths[j]) for j in case.skeleton.bones[:, 1]}
    given = every if "lengths" in oracles else {j: every[j] for j in KNOWN_BONES}
    result = fill(resolve_bone_lengths(ClipResult(clip=as_clip(case, tracks, confidence,
                                                                 given)), ratios),
                  BuildOptions())
    bones = result.bones
    assert bones is not None, "resolve_bone_lengths always sets the bones"
    lengths, filled = bones.lengths, result.uv
    if "root depth" in oracles:
        with true_root_depth(case.truth, case.skeleton.root):
            xyz = lift(filled, case.skeleton, lengths, case.camera, hand=case.hand).xyz
    else:
        xyz = lift(filled, case.skeleton, lengths, case.camera, hand=case.hand).xyz
    if "signs" in oracles:
        xyz = signs_oracle(xyz, filled, case, lengths)
    return xyz


def measure(cases, ratios: pa.Table) -> dict[frozenset[str], real_data.Errors] | None:
    """Errors of every oracle set pooled over a dataset's clips; ``None`` when it has none.

    Every oracle set sees the same noise and the same dropouts (one generator per set,
    seeded alike, drawn in the same order).
    """
    errors: dict[frozenset[str], real_data.Errors] = {}
    draws = {oracles: np.random.default_rng([NOISE_SEED, 1]) for oracles in ORACLE_SETS}
    for case in cases(np.random.default_rng(NOISE_SEED)):
        for oracles in ORACLE_SETS:
            xyz = lift_with(case, oracles, ratios, draws[oracles])
            errors.setdefault(oracles, real_data.Errors(case.skeleton)).add(case.truth, xyz)
    return errors or None


def section(key: str, title: str, cases, ratios: pa.Table) -> list[str]:
    """The decomposition table of one dataset."""
    lines = [f"## {title}", "", f"Constants: {PROVENANCE[key]}.", ""]
    errors = None if cases is None else measure(cases, ratios)
    if errors is None:
        return lines + ["Skipped: the data is absent (../shared/data).", ""]
    base = errors[frozenset()].summary()["all"]
    lines += ["| oracles | MPJPE | PA-MPJPE | MPJPE share removed |", "|---|---:|---:|---:|"]
    for oracles in ORACLE_SETS:
        s = errors[oracles].summary()["all"]
        removed = 1.0 - s["mpjpe"] / base["mpjpe"]
        lines.append(f"| {label(oracles)} | {s['mpjpe']:.1f} | {s['pa_mpjpe']:.1f} | "
                     f"{100 * removed:.0f} % |")
    return lines + [""]


def report(plan: dict) -> str:
    """The whole decomposition as markdown."""
    ratios = build_ratios()
    lines = ["# As a detector gives it, decomposed by oracles", "",
             "Generated by `benchmarks/detector_oracles.py`"
             + (" (--quick)" if plan is QUICK else "") + "; the input is "
             "`benchmarks/detector_pipeline.py`'s. Root-relative MPJPE and PA-MPJPE, mm, "
             "of the default lifting; the last row (every oracle) is the truth made "
             "length-consistent along its rays.", ""]
    for key, title, cases in datasets(plan):
        lines += section(key, title, cases, ratios)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Run the decomposition and print it."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="one view, one synthetic seed and motion")
    args = parser.parse_args(argv)
    sys.stdout.write(report(QUICK if args.quick else FULL) + "\n")


if __name__ == "__main__":
    main()
