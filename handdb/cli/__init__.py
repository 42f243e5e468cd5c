"""The ``handdb`` command line: build, query, serve, export and inspect a hand motion database.

Every command that touches a database takes ``--db`` (default ``./data/db`` or
``$HANDDB_DB``); commands that read raw input take ``--inbox`` (default ``./data/inbox`` or
``$HANDDB_INBOX``).
"""

from __future__ import annotations

import csv
import importlib
import json
import sys
import warnings
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.markup import escape

from handdb.build.orchestrators import DEFAULT_RUNNER, check_runner, runner_names
from handdb.errors import DamagedFileWarning, HanddbError, UnknownNameError
from handdb.gapfill import DEFAULT_METHOD as DEFAULT_GAP_FILL
from handdb.gapfill import METHODS as GAP_FILLING
from handdb.lifting import DEFAULT_METHOD as DEFAULT_LIFT
from handdb.lifting import METHODS as LIFTING
from handdb.lifting import MODEL_FIT
from handdb.paths import DEFAULT_DB, DEFAULT_INBOX

#: Sub-commands whose modules are imported only when they run, so that ``handdb --help``
#: and the light commands start without USD, scipy or matplotlib: name -> (module, the
#: module's Typer app or command function, the one-line help ``handdb --help`` lists).
LAZY_COMMANDS: dict[str, tuple[str, str, str]] = {
    "gapfill-eval": ("handdb.cli.gapfill", "gapfill_eval",
                     "Hide known points of full tracks, fill them with every method, print "
                     "the RMSE."),
    "export": ("handdb.cli.export", "export_clips",
               "Export clips, one file per clip, as USD, BVH, glTF, FBX, TRC or C3D."),
    "export-usd": ("handdb.cli.export", "export_usd",
                   "Export a clip as a UsdSkel animation with a skinned hand mesh."),
    "export-bvh": ("handdb.cli.export", "export_bvh",
                   "Export a clip's joint rotations as BVH."),
    "preview": ("handdb.cli.preview", "preview",
                "Draw a stored clip's contact sheet (camera and side views, labelled) as PNG."),
    "ratios": ("handdb.cli.ratios", "app",
               "Relative phalanx lengths from X-ray images and joint placement (Chaudhry et "
               "al.)."),
    "lift": ("handdb.cli.lift", "app", "Depth reconstruction."),
}


def load_command(name: str) -> Any:
    """Import the sub-command ``name`` of :data:`LAZY_COMMANDS`; return its click command.

    Typer builds the command with the click it runs on (newer Typers vendor their own),
    so this module names no click class itself.
    """
    module, attribute, _ = LAZY_COMMANDS[name]
    target = getattr(importlib.import_module(module), attribute)
    if not isinstance(target, typer.Typer):
        single = typer.Typer(add_completion=False)
        single.command(name)(target)
        target = single
    command = typer.main.get_command(target)
    command.name = name
    return command


class LazyGroup(typer.core.TyperGroup):
    """The ``handdb`` group, whose :data:`LAZY_COMMANDS` load only when they run.

    Listing them (``handdb --help``) reads their one-line help from the table.
    """

    def list_commands(self, ctx: Any) -> list[str]:
        """The eager commands, then the lazy ones."""
        return [*super().list_commands(ctx), *LAZY_COMMANDS]

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        """The command ``cmd_name``; a lazy one not yet loaded as a stub holding its help."""
        command = super().get_command(ctx, cmd_name)
        if command is None and cmd_name in LAZY_COMMANDS:
            short_help = LAZY_COMMANDS[cmd_name][2]
            return typer.core.TyperCommand(cmd_name, help=short_help, short_help=short_help)
        return command

    def resolve_command(self, ctx: Any, args: list[str]) -> tuple[str | None, Any,
                                                                            list[str]]:
        """The command that runs, a lazy one imported now."""
        name, command, rest = super().resolve_command(ctx, args)
        if name in LAZY_COMMANDS and name not in self.commands:
            command = self.commands[name] = load_command(name)
        return name, command, rest


app = typer.Typer(
    name="handdb",
    cls=LazyGroup,
    help="Build and query a hand motion database from 2D keypoint tracks and X-ray "
    "bone measurements.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=True)
out = Console()

Inbox = Annotated[str, typer.Option("--inbox", envvar="HANDDB_INBOX",
                                     help="Folder of raw inputs (clips, sidecars, X-ray CSVs).")]
Db = Annotated[str, typer.Option("--db", envvar="HANDDB_DB",
                                 help="Database folder or fsspec URL (e.g. s3://bucket/db).")]

#: Rows ``handdb sql`` shows in a table unless ``--max-rows`` says otherwise.
TABLE_ROWS = 40
#: Exit status when some inputs were quarantined but every other clip went through.
EXIT_QUARANTINED = 3
#: Exit status when a stage failed on a clip.
EXIT_FAILED = 1


class OutputFormat(StrEnum):
    """How ``handdb sql`` prints its result."""

    table = "table"
    csv = "csv"
    json = "json"


def one_of(names: tuple[str, ...]) -> str:
    """The choices of an option, for its help: ``"one of: a, b, c"``.

    The names come from the registries, which know them without importing the methods
    (:mod:`handdb.lifting.methods`, :mod:`handdb.gapfill.methods`), so ``--help`` stays fast.
    """
    return f"one of: {', '.join(names)}"


def print_error(error: Exception, label: str = "error") -> None:
    """Print ``error`` on one logical line, so that paths in it stay whole and literal."""
    console.print(f"[red]{label}:[/] {escape(str(error))}", soft_wrap=True)


def run_build(inbox: str, db: str, options=None, *, workers: int = 4,
              runner: str = DEFAULT_RUNNER, dask_address: str | None = None,
              quiet: bool = False):
    """Run the build (:func:`handdb.build.run_build`) showing its progress; return its summary.

    On a terminal the progress is a live display, elsewhere one line per event
    (:mod:`handdb.cli.progress`); ``quiet`` shows none.
    """
    from handdb.build import progress as build_progress
    from handdb.build import run_build as build_database
    from handdb.cli.progress import build_reporter

    if quiet:
        return build_database(inbox, db, options, runner=runner, workers=workers,
                              address=dask_address)
    with build_reporter(console) as reporter, build_progress.reporting(reporter):
        return build_database(inbox, db, options, runner=runner, workers=workers,
                              address=dask_address)


def _timing(timings: dict[str, float]) -> str:
    """The wall time of the whole build, beside the part of it spent in the clips.

    ``timings`` holds ``total`` (the whole build: planning, starting and stopping Prefect,
    the clips) and ``scan`` and ``clips``, the build's own work inside it
    (:data:`handdb.build.entry.TOTAL`).
    """
    from handdb.build.entry import TOTAL

    if TOTAL not in timings:
        return ""
    work = timings.get("scan", 0.0) + timings.get("clips", 0.0)
    return f" in {timings[TOTAL]:.1f} s ({work:.1f} s planning and processing clips)"


def print_summary(summary) -> None:
    """Print a build summary: clips, refusals, implausible results, ambiguous depths, failures."""
    console.print(
        f"[bold]built[/] {summary.db}: {summary.n_clips} clips in the inbox, "
        f"{len(summary.processed)} processed ({summary.n_frames} frames), "
        f"{len(summary.unchanged)} unchanged, "
        f"{len(summary.refusals)} refused, {len(summary.flagged)} flagged, "
        f"{len(summary.failed)} failed{_timing(summary.timings)}",
        soft_wrap=True,
    )
    if summary.flow_run_url:
        console.print(f"  Prefect run: {summary.flow_run_url}", soft_wrap=True)
    for repair in summary.repairs:
        console.print(f"  [yellow]repaired[/] {escape(repair)}", soft_wrap=True)
    for refusal in summary.refusals:
        console.print(f"  [yellow]quarantined[/] {refusal}", soft_wrap=True)
    for clip_id, reasons in summary.flagged.items():
        console.print(f"  [yellow]flagged[/] {clip_id}: {'; '.join(reasons)}", soft_wrap=True)
    for clip_id, note in summary.depth_ambiguous.items():
        console.print(f"  [yellow]depth ambiguous[/] {clip_id}: {note}", soft_wrap=True)
    for clip_id, error in summary.failed.items():
        console.print(f"  [red]failed[/] {clip_id}: {error}", soft_wrap=True)


@app.command()
def build(
    inbox: Inbox = DEFAULT_INBOX,
    db: Db = DEFAULT_DB,
    gap_fill: Annotated[str | None, typer.Option(
        help=f"Gap-filling method for every clip, {one_of(GAP_FILLING.names())} (default: "
        f"each clip's sidecar, else {DEFAULT_GAP_FILL}).")] = None,
    lift: Annotated[str | None, typer.Option(
        help=f"Lifting method for every clip, {one_of(LIFTING.names())} (default: each "
        f"clip's sidecar, else {DEFAULT_LIFT}).")] = None,
    usd: Annotated[bool, typer.Option(help="Export every clip as USD.")] = True,
    compare: Annotated[list[str] | None, typer.Option(
        help=f"Also validate this lifting method on clips with ground truth, "
        f"{one_of(LIFTING.names())} (repeatable; {MODEL_FIT} takes about a minute per "
        "clip).")] = None,
    workers: Annotated[int, typer.Option(min=1, help="Clips processed in parallel.")] = 4,
    runner: Annotated[str, typer.Option(
        help=f"Where clips run ({one_of(runner_names())}): thread (Prefect tasks in this "
        "process), dask (Prefect tasks on a local Dask cluster unless --dask-address is "
        "given), local (this process, without Prefect).")] = DEFAULT_RUNNER,
    dask_address: Annotated[str | None, typer.Option(
        help="Address of an existing Dask scheduler.")] = None,
) -> None:
    """Ingest new or changed clips from the inbox and run every stage on them.

    Exit status: 0 when every clip went through, 3 when some inputs were quarantined
    (the rest was built), 1 when a stage failed on a clip.
    """
    from handdb.build import BuildOptions

    options = BuildOptions(gap_fill=gap_fill, lift=lift, export_usd=usd,
                           compare=tuple(compare or ()))
    try:
        # checked here, before the stages are imported (seconds), so a mistyped name
        # answers at once; run_build checks again for callers of the library
        options.check()
        check_runner(runner)
        summary = run_build(inbox, db, options, workers=workers, runner=runner,
                            dask_address=dask_address)
    except HanddbError as exc:
        print_error(exc)
        raise typer.Exit(EXIT_FAILED) from None
    print_summary(summary)
    if summary.failed:
        raise typer.Exit(EXIT_FAILED)
    if summary.refusals:
        raise typer.Exit(EXIT_QUARANTINED)


@app.command()
def sql(
    statement: Annotated[str, typer.Argument(
        help="SQL; every table is a view of its name. '-' reads it from standard input.")],
    db: Db = DEFAULT_DB,
    format: Annotated[OutputFormat, typer.Option(
        "--format", "-f", help="table, csv (a header line, then rows) or json.")
    ] = OutputFormat.table,
    max_rows: Annotated[int, typer.Option(
        min=0, help="Rows a table shows: the first and last, and how many were left out; "
        "0 shows every row. csv and json print every row.")] = TABLE_ROWS,
    vertical: Annotated[bool, typer.Option(
        help="Print a table with one line per column, for wide rows.")] = False,
) -> None:
    """Run a SQL query against the database with DuckDB and print the result."""
    import shutil

    import duckdb

    from handdb.store.query import query

    if statement == "-":
        statement = sys.stdin.read()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", DamagedFileWarning)
            result = query(db, statement)
    except HanddbError as exc:
        print_error(exc)
        raise typer.Exit(EXIT_FAILED) from None
    except duckdb.Error as exc:
        print_error(exc, "SQL error")
        raise typer.Exit(EXIT_FAILED) from None
    for warning in caught:
        console.print(f"[yellow]warning:[/] {escape(str(warning.message))}", soft_wrap=True)
    if format is OutputFormat.csv:
        writer = csv.writer(sys.stdout, lineterminator="\n")
        writer.writerow(result.column_names)
        for batch in result.to_batches():
            writer.writerows(zip(*(column.to_pylist() for column in batch.columns), strict=True))
    elif format is OutputFormat.json:
        out.print_json(json.dumps(result.to_pylist(), default=str))
    else:
        # DuckDB's own rendering: NULL as NULL, widths that fit the terminal, elided rows
        # and columns counted.
        duckdb.connect().from_arrow(result).show(
            max_rows=max_rows or max(result.num_rows, 1),
            max_width=shutil.get_terminal_size().columns,
            render_mode="columns" if vertical else "rows")


@app.command("tables")
def list_tables() -> None:
    """List the database's tables and derived views, and what each holds."""
    from rich.table import Table

    from handdb.store import tables
    from handdb.store.query import derived_views

    grid = Table("name", "kind", "one row per / what it holds", show_lines=False)
    for name in tables.table_names():
        grid.add_row(name, "table", tables.table_spec(name).description)
    for name, description in derived_views().items():
        grid.add_row(name, "view", description)
    out.print(grid)
    out.print("Columns, their types and units: handdb describe NAME")


@app.command()
def describe(
    name: Annotated[str, typer.Argument(help="A table or view (see handdb tables).")],
    db: Db = DEFAULT_DB,
) -> None:
    """Print a table's columns: their type, whether they may be NULL, and what they hold.

    A table's columns come from its contract and need no database; a derived view's are
    read from the database at --db.
    """
    from rich.table import Table

    from handdb.store import tables
    from handdb.store.query import derived_views, query

    grid = Table("column", "type", "NULL", "what it holds (units)", title=name)
    if name in tables.table_names():
        for field in tables.schema(name):
            doc = field.metadata.get(b"doc", b"").decode() if field.metadata else ""
            grid.add_row(field.name, str(field.type), "yes" if field.nullable else "no", doc)
    elif name in derived_views():
        try:
            columns = query(db, "SELECT column_name, data_type, is_nullable, comment "
                                f"FROM duckdb_columns() WHERE table_name = '{name}' "
                                "ORDER BY column_index").to_pylist()
        except HanddbError as exc:
            print_error(exc)
            raise typer.Exit(EXIT_FAILED) from None
        for column in columns:
            grid.add_row(column["column_name"], column["data_type"],
                         "yes" if column["is_nullable"] else "no", column["comment"] or "")
    else:
        print_error(UnknownNameError("table or view", name,
                                     (*tables.table_names(), *derived_views())))
        raise typer.Exit(EXIT_FAILED)
    out.print(grid)


@app.command()
def serve(
    inbox: Inbox = DEFAULT_INBOX,
    db: Db = DEFAULT_DB,
    cron: Annotated[str | None, typer.Option(
        help="Cron schedule, e.g. '*/15 * * * *'.")] = None,
    interval: Annotated[float | None, typer.Option(
        min=1, help="Seconds between builds.")] = None,
) -> None:
    """Run the build on a schedule as a Prefect deployment.

    Uses the Prefect server at PREFECT_API_URL; when none is set, starts a local Prefect
    server (SQLite, loopback) for as long as this command runs.
    """
    if (cron is None) == (interval is None):
        console.print("[red]error:[/] give exactly one of --cron and --interval")
        raise typer.Exit(2)
    from handdb.build import load_orchestrator

    try:
        orchestrator = load_orchestrator()
    except HanddbError as exc:
        print_error(exc)
        raise typer.Exit(EXIT_FAILED) from None
    orchestrator.serve(inbox, db, cron=cron, interval=interval)


@app.command()
def demo(inbox: Inbox = DEFAULT_INBOX, db: Db = DEFAULT_DB) -> None:
    """Generate sample inputs, build the demo database and print what it holds."""
    from handdb.demo import describe_database, write_demo_inbox

    written = write_demo_inbox(Path(inbox))
    console.print(f"wrote {len(written)} sample inputs to {inbox}")
    try:
        summary = run_build(inbox, db)
    except HanddbError as exc:
        print_error(exc)
        raise typer.Exit(EXIT_FAILED) from None
    print_summary(summary)
    out.print(describe_database(db))
    if summary.failed:
        raise typer.Exit(EXIT_FAILED)


def main() -> None:
    """Entry point of the ``handdb`` command."""
    app()
