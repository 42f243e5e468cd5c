"""``handdb export`` (many clips, any format), ``handdb export-usd`` and ``export-bvh``.

Register on the main app with ``app.add_typer(export.app)`` (the commands join the main
app's) or one by one with ``app.command("export")(export.export_clips)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from handdb.errors import HanddbError, UnknownNameError
from handdb.export.formats import FORMATS, ExportOptions
from handdb.export.stored import export_stored_clip, export_stored_clips
from handdb.paths import DEFAULT_DB

app = typer.Typer(add_completion=False, no_args_is_help=True)

#: Exit status when some clips were skipped and every other was written (as ``handdb
#: build``'s when inputs were quarantined).
EXIT_SKIPPED = 3

Clip = Annotated[str, typer.Option("--clip", help="Id of the clip to export.")]
Db = Annotated[str, typer.Option("--db", envvar="HANDDB_DB",
                                 help="Database folder or fsspec URL (e.g. s3://bucket/db).")]
UsdOut = Annotated[Path, typer.Option("--out", help="Output file: .usda, .usdc, .usd or .usdz.")]
BvhOut = Annotated[Path, typer.Option("--out", help="Output .bvh file.")]
OutDir = Annotated[Path, typer.Option("--out", help="Output folder: one <clip_id>.<suffix> "
                                      "file per clip; created if missing.")]
Format = Annotated[str, typer.Option("--format", help="Export format: "
                                     f"{', '.join(FORMATS.names())} (docs/export.md).")]
ClipIds = Annotated[list[str] | None, typer.Argument(
    help="Clips to export; every clip of the database when none is given.",
    show_default=False)]


KeepLengths = Annotated[bool, typer.Option(
    "--keep-lengths", help="Give every bone its stored length (rigid bones, measured "
    "directions) instead of reproducing joints_3d exactly.")]


AtOrigin = Annotated[bool | None, typer.Option(
    "--at-origin/--camera-frame", show_default=False,
    help="Put the wrist of the first frame at the origin and the hand on the floor (Y up), "
    "or keep the camera's coordinates. Default: at the origin for USD, BVH, glTF and FBX, "
    "camera coordinates for TRC and C3D.")]


def _fail(exc: HanddbError) -> typer.Exit:
    typer.echo(f"error: {exc}", err=True)
    return typer.Exit(1)


def _export(db: str, clip: str, out: Path, format_names: tuple[str, ...],
            keep_lengths: bool = False, at_origin: bool | None = None) -> None:
    suffixes = tuple(suffix for name in format_names for suffix in FORMATS[name].suffixes)
    if out.suffix not in suffixes:
        raise typer.BadParameter(f"'{out}' must end in one of {', '.join(suffixes)}",
                                 param_hint="--out")
    try:
        written = export_stored_clip(db, clip, out, keep_lengths=keep_lengths,
                                     at_origin=at_origin)
    except HanddbError as exc:
        raise _fail(exc) from None
    typer.echo(str(written))


@app.command("export-usd")
def export_usd(clip: Clip, out: UsdOut, db: Db = DEFAULT_DB,
               keep_lengths: KeepLengths = False, at_origin: AtOrigin = None) -> None:
    """Export a clip as a UsdSkel animation with a skinned hand mesh."""
    _export(db, clip, out, ("usd", "usdz"), keep_lengths, at_origin)


@app.command("export-bvh")
def export_bvh(clip: Clip, out: BvhOut, db: Db = DEFAULT_DB,
               at_origin: AtOrigin = None) -> None:
    """Export a clip's joint rotations as BVH."""
    _export(db, clip, out, ("bvh",), at_origin=at_origin)


@app.command("export")
def export_clips(format_name: Format, out: OutDir, clip_ids: ClipIds = None,
                 db: Db = DEFAULT_DB, keep_lengths: KeepLengths = False,
                 at_origin: AtOrigin = None) -> None:
    """Export clips, one file per clip, as USD, BVH, glTF, FBX, TRC or C3D.

    Every clip of the database when none is named. Prints each file written; a clip the
    format cannot take is skipped with the reason (exit status 3 when any was).
    """
    if format_name not in FORMATS:
        raise typer.BadParameter(str(UnknownNameError(
            "export format", format_name, FORMATS.names())), param_hint="--format")
    skipped = 0
    try:
        for result in export_stored_clips(db, format_name, out, clip_ids or None,
                                          ExportOptions(keep_lengths=keep_lengths,
                                                        at_origin=at_origin)):
            if result.path is None:
                skipped += 1
                typer.echo(f"skipped {result.clip_id}: {result.skipped}", err=True)
            else:
                typer.echo(str(result.path))
    except HanddbError as exc:
        raise _fail(exc) from None
    if skipped:
        raise typer.Exit(EXIT_SKIPPED)
