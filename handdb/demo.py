"""The demo inbox: synthetic clips, the thesis's experiment and the paper's X-ray table.

Synthetic clips with exact ground truth come in every input format, beside the thesis's
clenching-hand experiment and the X-ray table of Chaudhry et al.

Every clip comes from the procedural hand of :mod:`handdb.synthetic`, so the demo
database can be validated against truth. Some clips have occluded and low-confidence
points so the gap-filling stage has work to do.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import numpy as np
from rich.console import Group
from rich.table import Table

from handdb.hand.skeletons import load_skeleton
from handdb.ingest import get_format
from handdb.store import tables
from handdb.store.database import Store
from handdb.synthetic import SyntheticClip, synthesize_clip, thesis_clench_clip

XRAY_SAMPLE = "chaudhry_table1.xray.csv"

#: The demo's marker clip: frames (the fit runs at about one frame per second), marker
#: noise and the share of markers hidden (about 15 of 21 visible, as in Zhao et al.).
MARKER_FRAMES = 45
MARKER_NOISE_MM = 1.0
MARKER_DROPOUT = 0.28
FIRST_QUERY = ("SELECT clip_id, method, round(avg(dz_mean), 2) AS mean_abs_dz, "
               "round(avg(mpjpe), 2) AS mpjpe FROM validation_joint "
               "GROUP BY ALL ORDER BY clip_id, mean_abs_dz")


@dataclass(frozen=True)
class DemoClip:
    """One demo clip: what to synthesise and how to write it."""

    clip_id: str
    motion: str
    n_frames: int
    track_format: str
    subject: str
    camera: str = "orthographic"
    seed: int = 0
    hand: str = "right"
    gaps: int = 0
    low_confidence: float = 0.0
    give_lengths: bool = True
    truth: bool = True


DEMO_CLIPS: tuple[DemoClip, ...] = (
    DemoClip("rapid-s01", "rapid", 400, "tracks_csv", "s01", seed=1, give_lengths=False),
    DemoClip("rapid-pinhole-s01", "rapid", 400, "tracks_csv", "s01", camera="pinhole", seed=1),
    DemoClip("wave-s02", "wave", 300, "openpose", "s02", seed=2, gaps=12),
    DemoClip("clench-s02", "clench", 150, "dlc", "s02", seed=2, gaps=8, low_confidence=0.03),
    DemoClip("random-s03", "random", 300, "mediapipe", "s03", seed=3, hand="left", gaps=10),
    DemoClip("rapid-occluded-s03", "rapid", 400, "tracks_csv", "s03", seed=3, gaps=30,
             low_confidence=0.02),
)


def _writer(format_name: str) -> Callable[..., None]:
    """The writer of a registered input format (every format the demo uses has one)."""
    write = get_format(format_name).write
    if write is None:
        raise ValueError(f"input format '{format_name}' has no writer")
    return write


def hide_points(uv: np.ndarray, n_gaps: int, rng: np.random.Generator,
                max_length: int = 25) -> np.ndarray:
    """A copy of ``uv`` (T, J, 2) with ``n_gaps`` runs of 1..``max_length`` frames hidden.

    Gaps fall on random joints inside the clip, never on its first frame.
    """
    hidden = uv.copy()
    n_frames, n_joints = uv.shape[:2]
    for _ in range(n_gaps):
        joint = rng.integers(n_joints)
        length = int(rng.integers(1, max_length + 1))
        start = int(rng.integers(1, max(2, n_frames - length)))
        hidden[start:start + length, joint] = np.nan
    return hidden


def _write_clip(inbox: Path, spec: DemoClip) -> list[Path]:
    clip = synthesize_clip(spec.motion, spec.n_frames, camera=spec.camera, seed=spec.seed,
                           hand=spec.hand)
    rng = np.random.default_rng(spec.seed + 1000)
    uv = hide_points(clip.uv, spec.gaps, rng)
    confidence = np.clip(rng.normal(0.9, 0.05, uv.shape[:2]), 0.0, 1.0)
    confidence[rng.random(uv.shape[:2]) < spec.low_confidence] = 0.2
    sidecar = clip.sidecar(subject=spec.subject)
    if not spec.give_lengths:
        del sidecar["bone_lengths"]
    return _write(inbox, spec.clip_id, clip, sidecar, spec.track_format, uv, confidence,
                  truth=spec.truth)


def _write(inbox: Path, clip_id: str, clip: SyntheticClip, sidecar: dict, track_format: str,
           uv: np.ndarray, confidence: np.ndarray | None, *, truth: bool) -> list[Path]:
    skeleton = load_skeleton(clip.skeleton)
    fmt = get_format(track_format)
    write = _writer(track_format)
    sidecar_path = inbox / f"{clip_id}.clip.json"
    sidecar_path.write_text(json.dumps(sidecar, indent=1))
    track_path = inbox / f"{clip_id}{fmt.suffix}"
    if track_format == "openpose":
        write(track_path, uv, confidence, skeleton, hand=clip.hand)
    elif track_format == "mediapipe":
        write(track_path, uv, confidence, skeleton, image_size=clip.image_size)
    elif track_format == "maya":
        write(track_path, clip.xyz, skeleton)
    else:
        write(track_path, uv, confidence, skeleton)
    written = [sidecar_path, track_path]
    if truth and track_format != "maya":
        truth_path = inbox / f"{clip_id}.truth.csv"
        _writer("truth_csv")(truth_path, clip.xyz, skeleton)
        written.append(truth_path)
    return written


def _write_marker_clip(inbox: Path, clip_id: str, n_frames: int, seed: int) -> list[Path]:
    """Write a 3D marker clip as a motion capture system gives it.

    About 15 of 21 markers are visible per frame, with 1 mm noise, and the sidecar gives
    no bone lengths: the fit calibrates the subject.
    """
    clip = synthesize_clip("rapid", n_frames, seed=seed)
    skeleton = load_skeleton(clip.skeleton)
    rng = np.random.default_rng(seed)
    markers = clip.xyz + rng.normal(0.0, MARKER_NOISE_MM, clip.xyz.shape)
    hidden = rng.random(markers.shape[:2]) < MARKER_DROPOUT
    hidden[:, skeleton.root] = False
    markers[hidden] = np.nan
    sidecar = {"skeleton": clip.skeleton, "hand": clip.hand, "fps": clip.fps,
               "subject": "s04", "units": clip.units}
    sidecar_path = inbox / f"{clip_id}.clip.json"
    sidecar_path.write_text(json.dumps(sidecar, indent=1))
    marker_path = inbox / f"{clip_id}{get_format('markers_csv').suffix}"
    _writer("markers_csv")(marker_path, markers, skeleton)
    truth_path = inbox / f"{clip_id}.truth.csv"
    _writer("truth_csv")(truth_path, clip.xyz, skeleton)
    return [sidecar_path, marker_path, truth_path]


def write_demo_inbox(inbox: Path) -> list[Path]:
    """Write the demo inputs into ``inbox`` (created if needed); return the paths written.

    Writing is deterministic: the same call gives byte-identical files, so a second demo
    build finds nothing changed.
    """
    inbox.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for spec in DEMO_CLIPS:
        written += _write_clip(inbox, spec)
    thesis = thesis_clench_clip()
    thesis_sidecar = thesis.sidecar(subject="thesis-maya-hand")
    thesis_sidecar["camera"] = {"model": "orthographic"}
    del thesis_sidecar["image"]
    written += _write(inbox, "thesis-clench", thesis, thesis_sidecar, "maya", thesis.uv, None,
                      truth=True)
    written += _write_marker_clip(inbox, "markers-s04", MARKER_FRAMES, seed=4)
    xray = inbox / XRAY_SAMPLE
    shutil.copyfile(str(files("handdb") / "data" / XRAY_SAMPLE), xray)
    written.append(xray)
    return written


def describe_database(db: str) -> Group:
    """A summary of the database for the terminal: tables, clips, paths, a query to try."""
    from handdb.store.query import query

    store = Store(db)
    counts = Table("table", "rows", "files", title=f"database {store.uri()}")
    for name in tables.table_names():
        n_files = len(store.table_files(name))
        n_rows = query(store, f"SELECT count(*) AS n FROM {name}").column("n")[0].as_py()
        counts.add_row(name, str(n_rows), str(n_files))
    clips = query(store, "SELECT clip_id, source_format, n_frames, n_joints, has_truth, "
                         "lift_method, usd_path FROM clips ORDER BY clip_id")
    listing = Table(*clips.column_names, title="clips")
    for row in clips.to_pylist():
        listing.add_row(*("" if v is None else str(v) for v in row.values()))
    n_frames = sum(clips.column("n_frames").to_pylist())
    hint = (f"{clips.num_rows} clips, {n_frames} frames. Try:\n"
            f"  .venv/bin/handdb sql --db {db} \"{FIRST_QUERY}\"")
    return Group(counts, listing, hint)
