"""How long ``handdb export --format fbx`` takes for one clip and for several.

FBX is written by Blender (:mod:`handdb.export.fbx`), whose start-up is most of a clip's
cost. Prints the median wall time of exporting the first clip, then the first ``--clips``
clips, of a built database, each in a fresh ``handdb`` process; then of Blender's
conversion alone of those clips' staged glTF files: one clip, the clips with a Blender
process each (how ``handdb export`` ran before batches), and the clips in one process.

Run: ``HANDDB_BLENDER=.venv-blender/bin/python .venv/bin/python benchmarks/bench_fbx.py
--db data/db [--clips 4] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.export import FORMATS  # noqa: E402
from handdb.export.fbx import FbxConversion, convert_to_fbx, stage_gltf  # noqa: E402
from handdb.export.formats import ExportOptions  # noqa: E402
from handdb.export.stored import placed_motion, read_stored_motion  # noqa: E402
from handdb.store.database import Store  # noqa: E402

#: Clips of the larger batch.
CLIPS = 4
#: Runs of each export; the median is printed.
REPEATS = 3


def export_seconds(db: str, clip_ids: list[str], repeats: int) -> float:
    """Median wall time (seconds) of ``handdb export --format fbx`` of ``clip_ids``."""
    times = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            subprocess.run([sys.executable, "-c", "from handdb.cli import main; main()",
                            "export", "--format", "fbx", "--out", out, "--db", db, *clip_ids],
                           check=True, capture_output=True)
            times.append(time.perf_counter() - start)
    return statistics.median(times)


def staged(db: str, clip_ids: list[str], folder: Path) -> list[FbxConversion]:
    """The clips' glTF files in ``folder``, placed as ``handdb export`` places them."""
    entry, options = FORMATS["fbx"], ExportOptions()
    conversions = []
    for clip_id in clip_ids:
        motion = placed_motion(entry, read_stored_motion(db, clip_id), options)
        conversions.append(stage_gltf(folder, clip_id, clip_id=clip_id, skeleton=motion.skeleton,
                                      xyz=motion.xyz, bone_lengths=motion.bone_lengths,
                                      fps=motion.fps, units=motion.units, hand=motion.hand))
    return conversions


def conversion_seconds(runs: dict[str, Callable[[], object]], repeats: int) -> dict[str, float]:
    """Median wall time (seconds) of each of ``runs``, the runs alternated."""
    times: dict[str, list[float]] = {label: [] for label in runs}
    for _ in range(repeats):
        for label, run in runs.items():
            start = time.perf_counter()
            run()
            times[label].append(time.perf_counter() - start)
    return {label: statistics.median(seconds) for label, seconds in times.items()}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", required=True)
    parser.add_argument("--clips", type=int, default=CLIPS)
    parser.add_argument("--repeats", type=int, default=REPEATS)
    args = parser.parse_args(argv)
    clip_ids = Store(args.db).partition_keys("clips")[:args.clips]
    print(f"| clips | median wall s ({args.repeats} runs) | s per clip |")
    print("|---:|---:|---:|")
    for batch in (clip_ids[:1], clip_ids):
        seconds = export_seconds(args.db, batch, args.repeats)
        print(f"| {len(batch)} | {seconds:.1f} | {seconds / len(batch):.1f} |")
    with tempfile.TemporaryDirectory() as folder:
        conversions = staged(args.db, clip_ids, Path(folder))
        runs = {
            "1 clip": lambda: convert_to_fbx(conversions[:1]),
            f"{len(clip_ids)} clips, a Blender process each":
                lambda: [convert_to_fbx([conversion]) for conversion in conversions],
            f"{len(clip_ids)} clips, one Blender process": lambda: convert_to_fbx(conversions),
        }
        print(f"\n| Blender's conversion alone | median wall s ({args.repeats} runs) |")
        print("|---|---:|")
        for label, seconds in conversion_seconds(runs, args.repeats).items():
            print(f"| {label} | {seconds:.1f} |")


if __name__ == "__main__":
    main()
