"""``handdb gapfill-eval``: score every gap-filling method on clips with complete tracks.

Clips come from the database (those whose every point is observed, e.g. the demo's
``rapid-s01``), an inbox (``--inbox``) or are synthesized (``--synthetic rapid``). Known
points are hidden under each mask, filled by each method and compared with the truth, in
the flow :mod:`handdb_flows.gapfill_eval` (one task per clip). Table ``gapfill_eval`` (one
partition per clip) and a Figure-4.6-like chart per clip (``<db>/reports/<clip_id>/
gapfill.png``) land in the database; ``--out`` also writes them to a standalone folder.
The command prints the RMSE of every method under every mask (pixels, over all hidden
points of all clips).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import pyarrow as pa
import pyarrow.parquet as pq
import typer
from rich.console import Console
from rich.table import Table

from handdb.gapfill import METHODS
from handdb.gapfill.evaluate import MASKS, RANDOM_MASK, THESIS_MASK, pooled_rmse
from handdb.gapfill.sources import (
    ClipSource,
    InboxSource,
    SyntheticSource,
    database_sources,
)
from handdb.ingest.inbox import discover
from handdb.paths import DEFAULT_DB
from handdb.store.database import Store

out = Console()

#: Masks used unless ``--mask`` says otherwise.
DEFAULT_MASKS = (THESIS_MASK, RANDOM_MASK)


def inbox_sources(inbox: Path) -> list[InboxSource]:
    """List the inbox's clips; say which files the inbox refused."""
    scan = discover(inbox)
    for refused in scan.refused:
        out.print(f"[yellow]skipped: {refused}[/]")
    return [InboxSource(entry) for entry in scan.clips]


def rmse_table(rows: pa.Table, masks: list[str], methods: list[str]) -> Table:
    """Tabulate the RMSE (pixels) per method and mask, pooled over the clips' rows."""
    rmse = pooled_rmse(rows)
    table = Table(title="gap filling: RMSE over hidden points, pixels")
    table.add_column("method")
    table.add_column("family")
    for mask in masks:
        table.add_column(mask, justify="right")
    for method in methods:
        cells = [f"{rmse[(mask, method)]:.2f}" if (mask, method) in rmse else "-"
                 for mask in masks]
        table.add_row(method, METHODS[method].family, *cells)
    return table


def _write_folder(folder: Path, rows: pa.Table, charts: dict[str, str], store: Store) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    pq.write_table(rows, folder / "gapfill_eval.parquet")
    for clip_id, chart in charts.items():
        store.fs.get(chart, str(folder / f"{clip_id}_gapfill.png"))


def gapfill_eval(
    db: Annotated[str, typer.Option("--db", envvar="HANDDB_DB", help=(
        "Database the rows and charts go to; its clips with complete tracks are scored "
        "unless --inbox or --synthetic is given."))] = DEFAULT_DB,
    inbox: Annotated[Path | None, typer.Option(
        help="Score the clips of this inbox with complete tracks instead.")] = None,
    synthetic: Annotated[str | None, typer.Option(
        help="Score synthesized clips of this motion (rapid, clench, wave, random) instead.")
    ] = None,
    frames: Annotated[int, typer.Option(help="Frames of each synthetic clip.")] = 400,
    seeds: Annotated[int, typer.Option(help="Number of synthetic clips.")] = 2,
    skeleton: Annotated[str, typer.Option(help="Skeleton of the synthetic clips.")] = "mediapipe21",
    mask: Annotated[list[str] | None, typer.Option(
        help=f"Mask, repeatable: {', '.join(MASKS)} (default: the first two).")] = None,
    method: Annotated[list[str] | None, typer.Option(
        help=f"Method, repeatable: {', '.join(METHODS.names())} (default: every method).")
    ] = None,
    seed: Annotated[int, typer.Option(help="Seed of the random-gaps mask.")] = 0,
    out_dir: Annotated[Path | None, typer.Option(
        "--out", help="Also write gapfill_eval.parquet and the charts to this folder.")] = None,
    runner: Annotated[str, typer.Option(
        help="prefect (one Prefect task per clip) or local (this process, without "
        "Prefect).")] = "prefect",
) -> None:
    """Hide known points of full tracks, fill them with every method, print the RMSE."""
    from handdb.build import load_orchestrator
    from handdb.gapfill.sources import evaluate_sources

    methods = list(method or METHODS)
    masks = list(mask or DEFAULT_MASKS)
    unknown = sorted(set(methods) - set(METHODS)) + sorted(set(masks) - set(MASKS))
    if unknown:
        raise typer.BadParameter(f"unknown method or mask: {', '.join(unknown)}")
    if runner not in ("prefect", "local"):
        raise typer.BadParameter(f"unknown runner '{runner}': use prefect or local")
    if inbox is not None and synthetic is not None:
        raise typer.BadParameter("give at most one of --inbox and --synthetic")
    sources: list[ClipSource]
    if synthetic is not None:
        sources = [SyntheticSource(synthetic, frames, s, skeleton) for s in range(seeds)]
    elif inbox is not None:
        sources = list(inbox_sources(inbox))
    else:
        sources = list(database_sources(db))
    if not sources:
        out.print("[red]no clip with complete tracks to evaluate[/]")
        raise typer.Exit(1)
    if runner == "local":
        summary = evaluate_sources(sources, db, masks, methods, seed)
    else:
        summary = load_orchestrator().gapfill_eval(sources, db, masks, methods, seed)
    for clip_id in summary.skipped:
        out.print(f"[yellow]skipped {clip_id}: its tracks have missing points (or its files "
                  "were refused), so hidden points could not be scored[/]")
    if not summary.charts:
        out.print("[red]no clip with complete tracks to evaluate[/]")
        raise typer.Exit(1)
    if out_dir is not None:
        _write_folder(out_dir, summary.table, summary.charts, Store(db))
    out.print(rmse_table(summary.table, masks, methods))
    out.print(f"wrote table gapfill_eval and {len(summary.charts)} chart(s) to {db}")

