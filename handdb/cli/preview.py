"""``handdb preview``: the full contact sheet of a stored clip, drawn on demand.

The build stores a text-free thumbnail per clip (``reports/<clip>/preview.png``, see
:mod:`handdb.export.thumbnail`); this command draws the labelled sheet of
:func:`handdb.export.preview.write_preview_png` (title, frame times, axes in the clip's
units, finger legend; filled joints marked, the ground truth faint beneath when the clip
has it) from the clip's ``joints_3d`` and ``truth_3d`` rows.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from handdb.errors import HanddbError
from handdb.export.sheet import DEFAULT_PREVIEW_FRAMES
from handdb.paths import DEFAULT_DB

Clip = Annotated[str, typer.Option("--clip", help="Id of the clip to draw.")]
Out = Annotated[Path, typer.Option("--out", help="Output .png file.")]
Db = Annotated[str, typer.Option("--db", envvar="HANDDB_DB",
                                 help="Database folder or fsspec URL (e.g. s3://bucket/db).")]
Frames = Annotated[int, typer.Option("--frames", min=1, help="Frames to show.")]


def preview(clip: Clip, out: Out, db: Db = DEFAULT_DB,
            frames: Frames = DEFAULT_PREVIEW_FRAMES) -> None:
    """Draw a stored clip's contact sheet (camera and side views, labelled) as PNG."""
    if out.suffix != ".png":
        raise typer.BadParameter(f"'{out}' must end in .png", param_hint="--out")
    from handdb.export.preview import write_preview_png
    from handdb.hand.skeletons import load_skeleton
    from handdb.store.dataset import load_clip, load_truth

    try:
        dataset = load_clip(db, clip)
        truth = load_truth(db, clip, dataset.position.shape[:2])
    except HanddbError as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(1) from None
    attrs = dataset.attrs
    method = f" ({attrs['lift_method']})" if "lift_method" in attrs else ""
    written = write_preview_png(out, skeleton=load_skeleton(attrs["skeleton"]),
                                xyz=dataset.position.values, units=attrs["units"],
                                fps=attrs["fps"], title=f"{clip}{method}", count=frames,
                                filled=dataset.filled.values, truth=truth)
    typer.echo(str(written))
