"""``handdb gapfill-eval``: score every gap-filling method on clips with full tracks.

Clips come from an inbox (only clips whose tracks are complete can be scored; with ground
truth they also get the occlusion mask) or are synthesized (``--synthetic rapid``). Known
points are hidden under each mask, filled by each method and compared with the truth. The
command prints the RMSE of every method under every mask (pixels, over all hidden points
of all clips), and writes table ``gapfill_eval`` as Parquet and a Figure-4.6-like chart
per clip and mask into ``--out``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import typer
from rich.console import Console
from rich.table import Table

from handdb.errors import InputError
from handdb.gapfill import METHODS, THESIS
from handdb.gapfill.evaluate import (
    MASKS,
    OCCLUSION_MASK,
    RANDOM_MASK,
    THESIS_MASK,
    Evaluation,
    evaluate_clip,
    plot_errors,
)
from handdb.readers.inbox import discover, load_clip
from handdb.skeletons import Skeleton, load_skeleton

app = typer.Typer(name="gapfill", no_args_is_help=True)
out = Console()

#: Masks used unless ``--mask`` says otherwise.
DEFAULT_MASKS = (THESIS_MASK, RANDOM_MASK)
#: Where results go unless ``--out`` says otherwise.
DEFAULT_OUT = Path("gapfill-eval")


@app.callback()
def gapfill() -> None:
    """Gap-filling evaluation."""


@dataclass(frozen=True)
class FullClip:
    """A clip with complete 2D tracks (and its 3D joints when known)."""

    clip_id: str
    uv: np.ndarray
    skeleton: Skeleton
    xyz: np.ndarray | None


def inbox_clips(inbox: Path) -> Iterator[FullClip]:
    """Yield the inbox's clips whose tracks are complete; say why others are skipped."""
    scan = discover(inbox)
    for refused in scan.refused:
        out.print(f"[yellow]skipped: {refused}[/]")
    for entry in scan.clips:
        try:
            clip = load_clip(entry)
        except InputError as exc:
            out.print(f"[yellow]skipped {entry.clip_id}: {exc}[/]")
            continue
        if not clip.observed.all():
            out.print(f"[yellow]skipped {clip.clip_id}: its tracks have missing points, "
                      "so hidden points could not be scored[/]")
            continue
        truth = clip.truth if clip.truth is not None and np.isfinite(clip.truth).all() else None
        yield FullClip(clip.clip_id, clip.uv, clip.skeleton, truth)


def synthetic_clips(motion: str, n_frames: int, seeds: int, skeleton: str) -> Iterator[FullClip]:
    """Yield ``seeds`` synthesized clips of ``motion``."""
    from handdb.synthetic.clips import synthesize_clip

    for seed in range(seeds):
        clip = synthesize_clip(motion, n_frames, skeleton=skeleton, seed=seed)
        yield FullClip(f"{motion}-{seed}", clip.uv, load_skeleton(skeleton), clip.xyz)


def rmse_table(evaluations: list[Evaluation], masks: list[str], methods: list[str]) -> Table:
    """Tabulate the RMSE (pixels) per method and mask, pooled over the clips."""
    table = Table(title="gap filling: RMSE over hidden points, pixels")
    table.add_column("method")
    table.add_column("family")
    for mask in masks:
        table.add_column(mask, justify="right")
    for method in methods:
        cells = []
        for mask in masks:
            squared = np.concatenate([
                e.errors[(mask, method)][e.hidden[mask]] ** 2 for e in evaluations
                if (mask, method) in e.errors])
            cells.append(f"{np.sqrt(np.nanmean(squared)):.2f}" if squared.size else "-")
        table.add_row(method, METHODS[method].family, *cells)
    return table


def gapfill_eval(
    inbox: Annotated[Path | None, typer.Option(
        help="Inbox of clips with complete tracks.")] = None,
    synthetic: Annotated[str | None, typer.Option(
        help="Synthesize clips of this motion (rapid, clench, wave, random).")] = None,
    frames: Annotated[int, typer.Option(help="Frames of each synthetic clip.")] = 400,
    seeds: Annotated[int, typer.Option(help="Number of synthetic clips.")] = 2,
    skeleton: Annotated[str, typer.Option(help="Skeleton of the synthetic clips.")] = "mediapipe21",
    mask: Annotated[list[str] | None, typer.Option(
        help=f"Mask, repeatable: {', '.join(MASKS)} (default: the first two).")] = None,
    method: Annotated[list[str] | None, typer.Option(
        help="Method, repeatable (default: every method).")] = None,
    seed: Annotated[int, typer.Option(help="Seed of the random-gaps mask.")] = 0,
    out_dir: Annotated[Path, typer.Option(
        "--out", help="Folder for gapfill_eval.parquet and the charts.")] = DEFAULT_OUT,
) -> None:
    """Hide known points of full tracks, fill them with every method, print the RMSE."""
    methods = list(method or METHODS)
    mask = list(mask or DEFAULT_MASKS)
    unknown = sorted(set(methods) - set(METHODS)) + sorted(set(mask) - set(MASKS))
    if unknown:
        raise typer.BadParameter(f"unknown method or mask: {', '.join(unknown)}")
    if (inbox is None) == (synthetic is None):
        raise typer.BadParameter("give exactly one of --inbox and --synthetic")
    clips = inbox_clips(inbox) if inbox is not None else synthetic_clips(
        synthetic, frames, seeds, skeleton)
    out_dir.mkdir(parents=True, exist_ok=True)
    evaluations, parts = [], []
    for clip in clips:
        masks = [m for m in mask if m != OCCLUSION_MASK or clip.xyz is not None]
        evaluation = evaluate_clip(clip.clip_id, clip.uv, clip.skeleton, masks=masks,
                                   methods=methods, xyz=clip.xyz, seed=seed)
        evaluations.append(evaluation)
        parts.append(evaluation.table)
        shown = [m for m in methods if METHODS[m].family == THESIS] + ["auto"]
        for name in masks:
            plot_errors(evaluation, name, clip.skeleton, out_dir / f"{clip.clip_id}_{name}.png",
                        methods=[m for m in shown if m in methods])
    if not evaluations:
        out.print("[red]no clip with complete tracks to evaluate[/]")
        raise typer.Exit(1)
    pq.write_table(pa.concat_tables(parts), out_dir / "gapfill_eval.parquet")
    out.print(rmse_table(evaluations, mask, methods))
    out.print(f"wrote {out_dir / 'gapfill_eval.parquet'} and {len(evaluations)} clip chart(s)")


app.command("gapfill-eval")(gapfill_eval)
