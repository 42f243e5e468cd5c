"""The per-clip pipeline as plain functions: what each build stage does to one clip.

Stages, in order: ingest (read and validate the clip's files) → bone lengths → gap fill →
lift → validate → export. The Prefect flow in ``flows/build.py`` runs each stage as a
task per clip; this module holds no orchestration, only the work and the assembly of a
clip's rows into the tables of ``schemas/tables``.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb import __version__, tables
from handdb.clip import Clip
from handdb.errors import InputError
from handdb.paths import SCHEMAS_DIR
from handdb.quarantine import Refusal
from handdb.readers import ClipEntry, load_clip, tracks_2d_table, truth_3d_table

PACKAGE_DIR = Path(__file__).resolve().parent


@dataclass(frozen=True)
class BuildOptions:
    """Parameters of a build that change what is computed for a clip.

    ``gap_fill`` and ``lift`` override the method every clip's sidecar asks for
    (``None``: the sidecar's choice, else the default method).
    """

    gap_fill: str | None = None
    lift: str | None = None
    export_usd: bool = True


@cache
def code_fingerprint() -> str:
    """SHA-256 over handdb's source and contracts: a rebuild key for code changes."""
    digest = hashlib.sha256()
    files = sorted([*PACKAGE_DIR.rglob("*.py"), *SCHEMAS_DIR.rglob("*.*")])
    for path in files:
        digest.update(path.relative_to(path.parents[1]).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def build_key(content_hash: str, options: BuildOptions, context: str = "") -> str:
    """Key under which a clip's rows are valid.

    It changes when the clip's files, the build options, the shared inputs a clip depends
    on (``context``, e.g. the hash of the joint ratios) or handdb's code change.
    """
    payload = json.dumps(
        {"content": content_hash, "options": asdict(options), "context": context,
         "code": code_fingerprint(), "version": __version__},
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()


@dataclass
class ClipResult:
    """Everything the stages produced for one clip, ready to be committed.

    Attributes
    ----------
    clip
        The ingested clip.
    build_key
        See :func:`build_key`.
    uv
        ``(T, J, 2) float64`` pixels used for lifting: observed, or filled; NaN if neither.
    filled
        ``(T, J) bool``: the point was filled.
    fill_method
        Gap-filling method, ``None`` until that stage ran.
    xyz
        ``(T, J, 3) float64`` lifted positions, clip units; ``None`` until lifting ran.
    extra_tables
        Further per-clip tables by name (``bone_lengths``, ``validation_joint``, ...).
    """

    clip: Clip
    build_key: str
    uv: np.ndarray
    filled: np.ndarray
    fill_method: str | None = None
    xyz: np.ndarray | None = None
    lift_method: str | None = None
    scale: np.ndarray | None = None
    sign_confidence: np.ndarray | None = None
    length_inconsistency: np.ndarray | None = None
    usd_path: str | None = None
    extra_tables: dict[str, pa.Table] = field(default_factory=dict)


def ingest(entry: ClipEntry, key: str) -> ClipResult | Refusal:
    """Read and validate the clip's files; a refusal names the file, line and field."""
    try:
        clip = load_clip(entry)
    except InputError as error:
        return Refusal.from_error(error, clip_id=entry.clip_id)
    return start_result(clip, key)


def start_result(clip: Clip, key: str) -> ClipResult:
    """A result holding only the ingested clip: observed points, nothing filled or lifted."""
    uv = np.where(clip.observed[..., None], clip.uv, np.nan)
    return ClipResult(clip=clip, build_key=key, uv=uv,
                      filled=np.zeros(clip.observed.shape, dtype=bool))


def _per_point(values: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
    if values is None:
        return np.full(shape, np.nan)
    return np.asarray(values, dtype=np.float64).reshape(shape)


def joints_3d_table(result: ClipResult) -> pa.Table:
    """Rows of ``joints_3d``: one per frame and joint of the clip's skeleton."""
    clip = result.clip
    n_frames, n_joints = clip.observed.shape
    n = n_frames * n_joints
    joint_index = np.tile(np.arange(n_joints, dtype=np.int32), n_frames)
    xyz = result.xyz if result.xyz is not None else np.full((n_frames, n_joints, 3), np.nan)
    scale = (np.repeat(result.scale, n_joints) if result.scale is not None
             else np.full(n, np.nan))
    filled = result.filled.reshape(n)
    fill_method = np.where(filled, result.fill_method or "", None)
    lifted = np.isfinite(xyz).all(axis=-1).reshape(n)
    return tables.from_columns("joints_3d", {
        "clip_id": clip.clip_id,
        "frame": np.repeat(np.arange(n_frames, dtype=np.int32), n_joints),
        "joint": np.asarray(clip.skeleton.joints, dtype=object)[joint_index],
        "joint_index": joint_index,
        "u": result.uv[..., 0].reshape(n),
        "v": result.uv[..., 1].reshape(n),
        "observed": clip.observed.reshape(n),
        "confidence": clip.confidence.reshape(n),
        "filled": filled,
        "fill_method": fill_method,
        "x": xyz[..., 0].reshape(n),
        "y": xyz[..., 1].reshape(n),
        "z": xyz[..., 2].reshape(n),
        "lift_method": np.where(lifted, result.lift_method or "", None),
        "scale": scale,
        "sign_confidence": _per_point(result.sign_confidence, (n,)),
        "length_inconsistency": _per_point(result.length_inconsistency, (n,)),
    })


def _relative(path: str, inbox: Path) -> str:
    try:
        return Path(path).resolve().relative_to(inbox.resolve()).as_posix()
    except ValueError:
        return str(path)


def clip_tables(result: ClipResult, inbox: Path) -> dict[str, pa.Table]:
    """Every per-clip table of the result, ready for :meth:`handdb.store.Store.commit_clip`."""
    clip = result.clip
    source_files = [_relative(f, inbox) for f in clip.source_files]
    out = {
        "clips": clips_table(result, source_files),
        "tracks_2d": tracks_2d_table(clip),
        "joints_3d": joints_3d_table(result),
        **result.extra_tables,
    }
    truth = truth_3d_table(clip)
    if truth is not None:
        out["truth_3d"] = truth
    return out


def clips_table(result: ClipResult, source_files: list[str]) -> pa.Table:
    """The clip's one row of ``clips``."""
    clip, spec = result.clip, result.clip.spec
    camera = spec.camera
    return tables.from_columns("clips", {
        "clip_id": [clip.clip_id],
        "content_hash": [clip.content_hash],
        "build_key": [result.build_key],
        "source_format": [clip.source_format],
        "source_files": [source_files],
        "skeleton": [spec.skeleton],
        "hand": [spec.hand],
        "fps": [spec.fps],
        "subject": [spec.subject],
        "units": [spec.units],
        "camera_model": [camera.model],
        "fx": [camera.fx], "fy": [camera.fy], "cx": [camera.cx], "cy": [camera.cy],
        "image_width": [spec.image_width],
        "image_height": [spec.image_height],
        "n_frames": [clip.n_frames],
        "n_joints": [clip.skeleton.n_joints],
        "n_observed": [int(clip.observed.sum())],
        "min_confidence": [spec.min_confidence],
        "gap_fill_method": [result.fill_method],
        "lift_method": [result.lift_method],
        "has_truth": [clip.truth is not None],
        "sidecar": [spec.raw],
        "usd_path": [result.usd_path],
        "handdb_version": [__version__],
    })
