"""``handdb export-usd`` and ``handdb export-bvh``: one stored clip to a file.

Register on the main app with ``app.add_typer(export.app)`` (the commands join the main
app's) or one by one with ``app.command("export-usd")(export.export_usd)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from handdb.errors import HanddbError
from handdb.export.stored import BVH_SUFFIX, export_stored_clip
from handdb.export.usd import LAYER_SUFFIXES, USDZ_SUFFIX
from handdb.paths import DEFAULT_DB

app = typer.Typer(add_completion=False, no_args_is_help=True)

Clip = Annotated[str, typer.Option("--clip", help="Id of the clip to export.")]
Db = Annotated[str, typer.Option("--db", envvar="HANDDB_DB",
                                 help="Database folder or fsspec URL (e.g. s3://bucket/db).")]
UsdOut = Annotated[Path, typer.Option("--out", help="Output file: .usda, .usdc, .usd or .usdz.")]
BvhOut = Annotated[Path, typer.Option("--out", help="Output .bvh file.")]


KeepLengths = Annotated[bool, typer.Option(
    "--keep-lengths", help="Give every bone its stored length (rigid bones, measured "
    "directions) instead of reproducing joints_3d exactly.")]


def _export(db: str, clip: str, out: Path, suffixes: tuple[str, ...],
            keep_lengths: bool = False) -> None:
    if out.suffix not in suffixes:
        raise typer.BadParameter(f"'{out}' must end in one of {', '.join(suffixes)}",
                                 param_hint="--out")
    try:
        written = export_stored_clip(db, clip, out, keep_lengths=keep_lengths)
    except HanddbError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    typer.echo(str(written))


@app.command("export-usd")
def export_usd(clip: Clip, out: UsdOut, db: Db = DEFAULT_DB,
               keep_lengths: KeepLengths = False) -> None:
    """Export a clip as a UsdSkel animation with a skinned hand mesh."""
    _export(db, clip, out, (*LAYER_SUFFIXES, USDZ_SUFFIX), keep_lengths)


@app.command("export-bvh")
def export_bvh(clip: Clip, out: BvhOut, db: Db = DEFAULT_DB) -> None:
    """Export a clip's joint rotations as BVH."""
    _export(db, clip, out, (BVH_SUFFIX,))
