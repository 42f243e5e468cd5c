"""``handdb lift compare``: every lifting method on one clip, set out like Table 4.1.

The clip comes from an inbox (``--inbox`` and ``--clip``; its sidecar must give the bone
lengths), gap filled as the build fills it (:func:`handdb.build.stages.fill`: the sidecar's
method, and a clip of independent images, such as DeepLabCut labelled data, filled and
lifted image by image, never as a time series), or is synthesized (``--synthetic rapid``,
or ``--synthetic thesis`` for the thesis's 100-frame clench). With ground truth the command
prints, per method, the mean root-relative ``|dZ|``, the bone-sign accuracy and the MPJPE,
then the per-joint mean ``|dZ|``; ``--chart`` also writes the comparison as a PNG.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from handdb.build.options import BuildOptions
from handdb.build.stages import ClipResult, fill
from handdb.clip import VIDEO, Camera
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, bone_length_array, load_skeleton
from handdb.ingest.inbox import discover, load_clip
from handdb.lifting import available_methods, lift
from handdb.synthetic.clips import synthesize_clip, thesis_clench_clip
from handdb.validation.depth import clip_summary, comparison_chart, validation_table

app = typer.Typer(name="lift", no_args_is_help=True, add_completion=False)
out = Console()

#: Frames of a synthesized clip.
SYNTHETIC_FRAMES = 400


@app.callback()
def lift_commands() -> None:
    """Depth reconstruction."""


def _inbox_clip(inbox: Path, clip_id: str):
    scan = discover(inbox)
    entries = [e for e in scan.clips if e.clip_id == clip_id]
    if not entries:
        known = ", ".join(e.clip_id for e in scan.clips) or "none"
        raise typer.BadParameter(f"no clip '{clip_id}' in {inbox} (clips: {known})")
    clip = load_clip(entries[0])
    if not clip.spec.bone_lengths:
        raise InputError(clip.spec.path, "gives no bone lengths; add them to compare lifts "
                         "outside a build", field="bone_lengths")
    filled = fill(ClipResult(clip=clip), BuildOptions())
    return (clip.clip_id, filled.uv, clip.skeleton,
            bone_length_array(clip.skeleton, clip.spec.bone_lengths), clip.spec.camera,
            clip.spec.hand, clip.truth, clip.spec.units, clip.sampling)


def _synthetic_clip(motion: str, camera: str, seed: int):
    clip = (thesis_clench_clip() if motion == "thesis"
            else synthesize_clip(motion, SYNTHETIC_FRAMES, camera=camera, seed=seed))
    skeleton = load_skeleton(clip.skeleton)
    cam = Camera(**clip.camera) if clip.camera["model"] == "pinhole" else Camera()
    return (f"{motion}-{camera}-{seed}", clip.uv, skeleton,
            bone_length_array(skeleton, clip.bone_lengths), cam, clip.hand, clip.xyz,
            clip.units, VIDEO)


def _number(value: float | None) -> str:
    """Three significant digits, or a dash where the method gave no value."""
    return "-" if value is None or value != value else f"{value:.3g}"


def _print_tables(clip_id: str, table, skeleton: Skeleton, units: str) -> None:
    summary = Table(title=f"{clip_id}: depth against ground truth")
    for heading in ("method", f"mean |dZ| ({units})", "sign accuracy", f"MPJPE ({units})"):
        summary.add_column(heading, justify="left" if heading == "method" else "right")
    for method, f in sorted(clip_summary(table).items(), key=lambda kv: kv[1]["dz_mean"]):
        summary.add_row(method, _number(f["dz_mean"]), f"{f['sign_accuracy']:.1%}",
                        _number(f["mpjpe"]))
    out.print(summary)
    rows = table.to_pylist()
    methods = list(dict.fromkeys(r["method"] for r in rows))
    values = {(r["method"], r["joint"]): r for r in rows}
    joints = Table(title=f"mean |dZ| per joint ({units}), Table 4.1's average column")
    joints.add_column("id", justify="right")
    joints.add_column("joint")
    for method in methods:
        joints.add_column(method, justify="right")
    for j, joint in enumerate(skeleton.joints):
        cells = [_number(values[(m, joint)]["dz_mean"]) for m in methods]
        joints.add_row(str(skeleton.ids[j]), joint, *cells)
    out.print(joints)


@app.command()
def compare(
    inbox: Annotated[Path | None, typer.Option(help="Inbox folder holding the clip.")] = None,
    clip: Annotated[str | None, typer.Option(help="Clip id in the inbox.")] = None,
    synthetic: Annotated[str | None, typer.Option(
        help="Synthesize instead: clench, rapid, wave, random, or thesis.")] = None,
    camera: Annotated[str, typer.Option(help="Camera of a synthesized clip.")] = "orthographic",
    seed: Annotated[int, typer.Option(help="Seed of a synthesized clip.")] = 0,
    chart: Annotated[Path | None, typer.Option(help="Write the comparison as a PNG.")] = None,
) -> None:
    """Lift one clip with every method and compare them with its ground truth."""
    if synthetic is not None:
        clip_id, uv, skeleton, lengths, cam, hand, truth, units, sampling = _synthetic_clip(
            synthetic, camera, seed)
    elif inbox is not None and clip is not None:
        clip_id, uv, skeleton, lengths, cam, hand, truth, units, sampling = _inbox_clip(
            inbox, clip)
    else:
        raise typer.BadParameter("give --inbox and --clip, or --synthetic")
    results = {m: lift(uv, skeleton, lengths, cam, method=m, hand=hand, sampling=sampling)
               for m in available_methods()}
    for method, result in results.items():
        if result.note:
            out.print(f"[yellow]{method}: {result.note}[/]")
    if truth is None:
        out.print(f"{clip_id} has no ground truth; lifted with "
                  f"{', '.join(results)} but nothing to compare against")
        return
    table = validation_table(clip_id, truth, results, skeleton, units)
    _print_tables(clip_id, table, skeleton, units)
    if chart is not None:
        chart.write_bytes(comparison_chart(clip_id, table, skeleton))
        out.print(f"chart: {chart}")
