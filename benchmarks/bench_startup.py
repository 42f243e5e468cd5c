"""How long the command line takes to start (issue 16: ``handdb --help`` and ``handdb sql``
under 1 s, an empty build within 5 s).

Prints the median wall time of a few runs of each command, each in a fresh interpreter,
beside the floor of starting Python itself. The ``sql`` runs query a database of one
small Parquet table made here, so the figure includes DuckDB opening real files.

With ``--scan-db DB``, also prints how long queries take that scan ``joints_3d`` of a
database holding ``--copies`` copies of DB's ``joints_3d`` files (in this process, the
connection made once): the views read every column of the files they scan, a cost that
grows with the table, where the start-up saved by not importing ``pyarrow.dataset`` is
fixed.

Run: ``.venv/bin/python benchmarks/bench_startup.py [--repeats N] [--scan-db data/db
[--copies 40]]``.
"""

from __future__ import annotations

import argparse
import shutil
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
#: Copies of the scanned database's ``joints_3d`` files in the scan measurement.
COPIES = 40
#: Queries of the scan measurement.
SCANS = ("SELECT count(*) FROM joints_3d", "SELECT avg(x) FROM joints_3d",
         "SELECT clip_id, avg(x), avg(y), avg(z) FROM joints_3d GROUP BY ALL",
         "SELECT * FROM joints_3d WHERE frame = 10")


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


def copied_joints(source: Path, folder: Path, copies: int) -> Path:
    """A database in ``folder`` whose ``joints_3d`` is ``copies`` copies of ``source``'s."""
    table = folder / "scanned" / "joints_3d"
    table.mkdir(parents=True)
    for copy in range(copies):
        for path in sorted((source / "joints_3d").glob("*.parquet")):
            shutil.copyfile(path, table / f"{copy}-{path.name}")
    return folder / "scanned"


def print_scans(db: Path, repeats: int) -> None:
    """Print the median wall time of each of :data:`SCANS` on one read-only connection."""
    from handdb.store.query import connect

    with connect(str(db), read_only=True) as con:
        ((rows,),) = con.sql("SELECT count(*) FROM joints_3d").fetchall()
        print(f"\n| query, {rows} rows of joints_3d | median wall s ({repeats} runs) |")
        print("|---|---:|")
        for sql in SCANS:
            times = []
            for _ in range(repeats):
                start = time.perf_counter()
                con.sql(sql).fetchall()
                times.append(time.perf_counter() - start)
            print(f"| `{sql}` | {statistics.median(times):.2f} |")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=REPEATS)
    parser.add_argument("--scan-db", type=Path)
    parser.add_argument("--copies", type=int, default=COPIES)
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
        if args.scan_db is not None:
            print_scans(copied_joints(args.scan_db, Path(tmp), args.copies), args.repeats)


if __name__ == "__main__":
    main()
