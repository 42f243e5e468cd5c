"""Build a database as the command line does, on a chosen runner, for the tests."""

from __future__ import annotations

from pathlib import Path

from handdb.build import BuildOptions, BuildSummary, run_build


def run(inbox: str | Path, db: str, *, runner: str = "thread", workers: int = 2,
        address: str | None = None, **options) -> BuildSummary:
    """:func:`handdb.build.run_build` with ``options`` as keyword arguments of
    :class:`~handdb.build.BuildOptions` (``compare`` as any sequence)."""
    if "compare" in options:
        options["compare"] = tuple(options["compare"])
    return run_build(str(inbox), db, BuildOptions(**options), runner=runner, workers=workers,
                     address=address)
