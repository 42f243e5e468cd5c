"""How long the command line takes to start (issue 16: ``handdb --help`` and ``handdb sql``
under 1 s, an empty build within 5 s).

Prints the median wall time of a few runs of each command, each in a fresh interpreter,
beside the floor of starting Python itself. The ``sql`` runs query a database of one
small Parquet table made here, so the figure includes DuckDB opening real files.

Run: ``.venv/bin/python benchmarks/bench_startup.py [--repeats N]``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Runs of each command; the median is printed.
REPEATS = 5
#: Issue 16's targets, wall time.
TARGETS = {"handdb --help": "< 1 s", 'handdb sql "SELECT 1"': "< 1 s",
           "handdb build, empty inbox": "<= 5 s"}


def wall_time(argv: list[str], repeats: int) -> float:
    """Median wall time (seconds) of running ``argv`` ``repeats`` times."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def small_database(folder: Path) -> Path:
    """A database folder holding one empty Parquet file per table, as a build writes them."""
    import pyarrow.parquet as pq

    from handdb.store import tables

    for name in tables.table_names():
        table_dir = folder / "db" / name
        table_dir.mkdir(parents=True)
        pq.write_table(tables.empty(name), table_dir / "part-0.parquet")
    return folder / "db"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=REPEATS)
    args = parser.parse_args(argv)
    cli = [sys.executable, "-c", "from handdb.cli import main; main()"]
    with tempfile.TemporaryDirectory() as tmp:
        db = small_database(Path(tmp))
        inbox = Path(tmp) / "inbox"
        inbox.mkdir()
        commands = {
            "python -c pass (floor)": [sys.executable, "-c", "pass"],
            "handdb --help": [*cli, "--help"],
            "handdb build --help": [*cli, "build", "--help"],
            'handdb sql "SELECT 1"': [*cli, "sql", "SELECT 1", "--db", str(db)],
            "handdb lift --help (loads lifting)": [*cli, "lift", "--help"],
            "handdb build, empty inbox": [*cli, "build", "--inbox", str(inbox),
                                          "--db", str(Path(tmp) / "built")],
        }
        print(f"| command | median wall s ({args.repeats} runs) | target |")
        print("|---|---:|---|")
        for label, command in commands.items():
            seconds = wall_time(command, args.repeats)
            target = TARGETS.get(label, "")
            print(f"| {label} | {seconds:.2f} | {target} |")


if __name__ == "__main__":
    main()
