"""The per-clip pipeline as plain functions: what each build stage does to one clip.

Stages, in order: ingest (read and validate the clip's files) → bone lengths → gap fill →
lift → validate → export. Each takes a :class:`ClipResult` and returns a new one (or a
:class:`~handdb.store.quarantine.Refusal` when the clip's input cannot be used). The Prefect
flow in ``flows/build.py`` runs each stage as a task; this module holds no orchestration,
only the work and the assembly of a clip's rows into the tables of ``schemas/tables``.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from functools import cache, wraps
from pathlib import Path
from typing import Any, Concatenate, ParamSpec, TypeVar

import numpy as np
import pyarrow as pa

from handdb import __version__
from handdb.clip import METERS_PER_UNIT, Clip
from handdb.errors import BoneLengthError, InputError, StageError
from handdb.export.preview import write_preview_png
from handdb.export.usd import export_clip_usd
from handdb.gapfill import DEFAULT_METHOD as DEFAULT_GAP_FILL
from handdb.gapfill import FillResult, UnknownMethodError, fill_gaps
from handdb.ingest import (
    ClipEntry,
    load_clip,
    tracks_2d_table,
    truth_3d_table,
    xray,  # noqa: F401  (xray registers its inbox format)
)
from handdb.lengths.bone_lengths import BoneLengths, bone_lengths_table, clip_bone_lengths
from handdb.lifting import DEFAULT_METHOD as DEFAULT_LIFT
from handdb.lifting import LiftResult, available_methods, lift
from handdb.markers.calibration import calibrated_bone_lengths
from handdb.markers.fit import MarkerFit, fit_markers, joint_angles_table, joint_motion
from handdb.markers.tables import markers_3d_table
from handdb.paths import SCHEMAS_DIR
from handdb.store import tables
from handdb.store.database import Store
from handdb.store.quarantine import Refusal
from handdb.validation.depth import comparison_chart, markdown_summary, validation_table

PACKAGE_DIR = Path(__file__).resolve().parent

#: Lifting methods compared against ground truth for every 2D clip that has it.
VALIDATED_METHODS: tuple[str, ...] = ("thesis", "thesis-nocheck", DEFAULT_LIFT)

#: The method name of positions fitted to 3D markers (Zhao et al. 2012).
MARKER_FIT = "marker-fit"

#: The skeleton the kinematic hand model of the marker fit is built on.
MARKER_SKELETON = "mediapipe21"

#: Folders of the database that hold files other than tables.
USD_DIR, REPORTS_DIR = "usd", "reports"


@dataclass(frozen=True)
class BuildOptions:
    """Parameters of a build that change what is computed for a clip.

    ``gap_fill`` and ``lift`` override the method every clip's sidecar asks for
    (``None``: the sidecar's choice, else the default method). ``compare`` names lifting
    methods validated beside :data:`VALIDATED_METHODS` on clips with ground truth (e.g.
    ``model-fit``, which costs about a minute per clip).
    """

    gap_fill: str | None = None
    lift: str | None = None
    export_usd: bool = True
    compare: tuple[str, ...] = ()


@cache
def code_fingerprint() -> str:
    """SHA-256 over handdb's source and contracts: a rebuild key for code changes."""
    digest = hashlib.sha256()
    for path in sorted([*PACKAGE_DIR.rglob("*.py"), *SCHEMAS_DIR.rglob("*.*")]):
        digest.update(path.relative_to(path.parents[1]).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def build_key(content_hash: str, options: BuildOptions, context: str = "") -> str:
    """Key under which a clip's rows are valid.

    It changes when the clip's files, the build options, the shared inputs a clip depends
    on (``context``: the hash of the joint ratios) or handdb's code change.
    """
    payload = json.dumps(
        {"content": content_hash, "options": asdict(options), "context": context,
         "code": code_fingerprint(), "version": __version__},
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()


def table_hash(table: pa.Table) -> str:
    """SHA-256 of a table's rows, for :func:`build_key` contexts."""
    return hashlib.sha256(json.dumps(table.to_pylist(), sort_keys=True,
                                     default=str).encode()).hexdigest()


@dataclass(frozen=True)
class ClipResult:
    """Everything the stages produced for one clip, ready to be committed."""

    clip: Clip
    build_key: str
    bones: BoneLengths | None = None
    fill: FillResult | None = None
    lifted: LiftResult | None = None
    fit: MarkerFit | None = None
    validation: pa.Table | None = None
    report: str | None = None
    usd_path: str | None = None

    @property
    def uv(self) -> np.ndarray:
        """``(T, J, 2) float64`` pixels used for lifting: observed or filled, else NaN."""
        if self.fill is not None:
            return self.fill.uv
        return np.where(self.clip.observed[..., None], self.clip.uv, np.nan)


T = TypeVar("T")
P = ParamSpec("P")


def passes_refusals(
    stage: Callable[Concatenate[ClipResult, P], T],
) -> Callable[Concatenate[ClipResult | Refusal, P], T | Refusal]:
    """Let a stage take a refused clip and hand the refusal on untouched.

    A clip refused by an earlier stage goes down the rest of the chain unchanged, so it
    ends in the ``quarantine`` table with the reason the first refusing stage gave.
    """
    @wraps(stage)
    def run(result: ClipResult | Refusal, *args: P.args, **kwargs: P.kwargs) -> T | Refusal:
        if isinstance(result, Refusal):
            return result
        return stage(result, *args, **kwargs)

    return run


def _stage_output(value: T | None, stage: str, result: ClipResult) -> T:
    """Return what an earlier stage produced, or raise if that stage has not run."""
    if value is None:
        raise StageError(f"clip '{result.clip.clip_id}': the {stage} stage has not run")
    return value


def _refuse(error: Exception, result: ClipResult, field: str | None = None) -> Refusal:
    spec = result.clip.spec
    if isinstance(error, InputError):
        return Refusal.from_error(error, clip_id=spec.clip_id)
    return Refusal(file=spec.path, reason=str(error), error_type=type(error).__name__,
                   field=field, clip_id=spec.clip_id)


def _method(choice: str | None, sidecar: dict[str, Any], default: str) -> tuple[str, dict]:
    """The method to run and its parameters: the build's override, the sidecar, the default."""
    if choice is not None:
        return choice, {}
    params = {k: v for k, v in sidecar.items() if k != "method"}
    return sidecar.get("method", default), params


def ingest(entry: ClipEntry, key: str) -> ClipResult | Refusal:
    """Read and validate the clip's files; a refusal names the file, line and field."""
    try:
        clip = load_clip(entry)
    except InputError as error:
        return Refusal.from_error(error, clip_id=entry.clip_id)
    return ClipResult(clip=clip, build_key=key)


@passes_refusals
def resolve_bone_lengths(result: ClipResult, ratios: pa.Table | None) -> ClipResult | Refusal:
    """Give every bone of the clip a length, or refuse the clip when none can be had.

    Marker clips pass: their fit calibrates the subject itself (:func:`fit_marker_clip`).
    """
    if result.clip.markers is not None:
        return result
    if ratios is not None and ratios.num_rows == 0:
        ratios = None
    try:
        bones = clip_bone_lengths(result.clip, ratios)
    except BoneLengthError as error:
        return _refuse(error, result, field="bone_lengths")
    return replace(result, bones=bones)


@passes_refusals
def fill(result: ClipResult, options: BuildOptions) -> ClipResult | Refusal:
    """Fill the clip's missing 2D points with the chosen gap-filling method.

    Marker clips pass: the model fit bridges missing markers itself.
    """
    clip = result.clip
    if clip.markers is not None:
        return result
    method, params = _method(options.gap_fill, clip.spec.gap_fill, DEFAULT_GAP_FILL)
    try:
        filled = fill_gaps(clip.uv, clip.observed, clip.skeleton, method, **params)
    except (UnknownMethodError, TypeError, ValueError) as error:
        return _refuse(error, result, field="gap_fill")
    return replace(result, fill=filled)


@passes_refusals
def lift_clip(result: ClipResult, options: BuildOptions) -> ClipResult | Refusal:
    """Lift the filled 2D points to 3D with the chosen method (marker clips: fit them)."""
    clip = result.clip
    if clip.markers is not None:
        return fit_marker_clip(result)
    method, params = _method(options.lift, clip.spec.lift, DEFAULT_LIFT)
    if method not in available_methods():
        return _refuse(ValueError(f"unknown lifting method '{method}'; known: "
                                  f"{', '.join(available_methods())}"), result, field="lift")
    try:
        bones = _stage_output(result.bones, "bone lengths", result)
        lifted = lift(result.uv, clip.skeleton, bones.lengths, clip.spec.camera,
                      method=method, hand=clip.spec.hand, **params)
    except (TypeError, ValueError) as error:
        return _refuse(error, result, field="lift")
    return replace(result, lifted=lifted)


def _fitted_bone_lengths(fit: MarkerFit, clip: Clip) -> BoneLengths:
    """The bone lengths of a marker fit, in clip units, with their source."""
    spec = clip.spec
    if fit.calibration is not None:
        return calibrated_bone_lengths(fit.calibration, spec.units)
    skeleton = clip.skeleton
    lengths = np.full(skeleton.n_joints, np.nan)
    lengths[skeleton.bones[:, 1]] = (fit.model.bone_lengths
                                     / (METERS_PER_UNIT[spec.units] * 1000.0))
    given = [j in spec.bone_lengths for j in skeleton.joints]
    sources = tuple(None if j == skeleton.root else "given" if g else "anthropometric"
                    for j, g in enumerate(given))
    details = tuple(None if j == skeleton.root else f"bone_lengths in {spec.path}" if g
                    else "the hand model's template" for j, g in enumerate(given))
    return BoneLengths(skeleton=skeleton, units=spec.units, lengths=lengths, sources=sources,
                       details=details, residuals=np.full(skeleton.n_joints, np.nan),
                       n_frames=np.zeros(skeleton.n_joints, dtype=np.int64))


def fit_marker_clip(result: ClipResult) -> ClipResult | Refusal:
    """Fit the kinematic hand model to the clip's 3D markers (Zhao et al. 2012).

    Without bone lengths in the sidecar, the subject is calibrated from the clip first.
    The sidecar's ``lift`` parameters go to :func:`handdb.markers.fit.fit_markers`.
    """
    clip, spec = result.clip, result.clip.spec
    markers = _stage_output(clip.markers, "marker ingest", result)
    if spec.skeleton != MARKER_SKELETON:
        return _refuse(ValueError(f"marker clips use the {MARKER_SKELETON} marker set (the "
                                  f"21 markers of Zhao et al.), not '{spec.skeleton}'"),
                       result, field="skeleton")
    params = {k: v for k, v in spec.lift.items() if k != "method"}
    try:
        fit = fit_markers(markers, hand=spec.hand, units=spec.units,
                          bone_lengths=spec.bone_lengths or None, **params)
    except (TypeError, ValueError) as error:
        return _refuse(error, result, field="lift")
    n_frames, n_joints = clip.observed.shape
    lifted = LiftResult(xyz=fit.joints, sign_confidence=np.full((n_frames, n_joints), np.nan),
                        length_inconsistency=np.full((n_frames, n_joints), np.nan),
                        scale=np.full(n_frames, np.nan), method=MARKER_FIT)
    return replace(result, fit=fit, lifted=lifted, bones=_fitted_bone_lengths(fit, clip))


@passes_refusals
def validate(result: ClipResult, options: BuildOptions) -> ClipResult:
    """Compare the lifting methods against the clip's ground truth, if it has any."""
    clip = result.clip
    if clip.truth is None:
        return result
    lifted = _stage_output(result.lifted, "lift", result)
    bones = _stage_output(result.bones, "bone lengths", result)
    estimates: dict[str, LiftResult | np.ndarray] = {lifted.method: lifted}
    methods = (*VALIDATED_METHODS, *options.compare) if clip.markers is None else ()
    for method in methods:
        if method not in estimates:
            estimates[method] = lift(result.uv, clip.skeleton, bones.lengths,
                                     clip.spec.camera, method=method, hand=clip.spec.hand)
    table = validation_table(clip.clip_id, clip.truth, estimates, clip.skeleton, clip.spec.units)
    return replace(result, validation=table, report=markdown_summary(clip.clip_id, table))


def _put(store: Store, local: Path, *parts: str) -> str:
    """Move a local file into the database; return its path relative to the database.

    Within one local filesystem the move is a rename (atomic); across filesystems it is a
    copy. A file cut short by a killed build belongs to an uncommitted clip, which the
    next build writes again.
    """
    store.fs.makedirs(store.path(*parts[:-1]), exist_ok=True)
    if store.is_local:
        shutil.move(local, store.path(*parts))
    else:
        store.fs.put_file(str(local), store.path(*parts))
    return "/".join(parts)


@passes_refusals
def export(result: ClipResult, store: Store, options: BuildOptions) -> ClipResult:
    """Write the clip's USD animation, preview sheet and validation chart into the database.

    A clip with joints that could not be lifted is not exported (``usd_path`` stays null).
    """
    clip = result.clip
    lifted = _stage_output(result.lifted, "lift", result)
    bones = _stage_output(result.bones, "bone lengths", result)
    if not options.export_usd or not np.isfinite(lifted.xyz).all():
        return result
    spec = clip.spec
    with tempfile.TemporaryDirectory() as scratch:
        scratch_dir = Path(scratch)
        rotations = joint_motion(result.fit, spec.units) if result.fit is not None else None
        usd = export_clip_usd(scratch_dir / f"{clip.clip_id}.usd", clip_id=clip.clip_id,
                              skeleton=clip.skeleton, xyz=lifted.xyz,
                              bone_lengths=bones.lengths, fps=spec.fps,
                              units=spec.units, hand=spec.hand, rotations=rotations)
        usd_path = _put(store, usd, USD_DIR, usd.name)
        preview = write_preview_png(scratch_dir / "preview.png", skeleton=clip.skeleton,
                                    xyz=lifted.xyz, units=spec.units, fps=spec.fps,
                                    title=f"{clip.clip_id} ({lifted.method})")
        _put(store, preview, REPORTS_DIR, clip.clip_id, "preview.png")
        if result.validation is not None:
            chart = scratch_dir / "depth.png"
            chart.write_bytes(comparison_chart(clip.clip_id, result.validation, clip.skeleton))
            _put(store, chart, REPORTS_DIR, clip.clip_id, "depth.png")
    return replace(result, usd_path=usd_path)


def _flat(values: np.ndarray | None, n: int) -> np.ndarray:
    if values is None:
        return np.full(n, np.nan)
    return np.asarray(values, dtype=np.float64).reshape(n)


def joints_3d_table(result: ClipResult) -> pa.Table:
    """Rows of ``joints_3d``: one per frame and joint of the clip's skeleton."""
    clip, lifted = result.clip, result.lifted
    n_frames, n_joints = clip.observed.shape
    n = n_frames * n_joints
    joint_index = np.tile(np.arange(n_joints, dtype=np.int32), n_frames)
    uv = result.uv.reshape(n, 2)
    if result.fill is not None:
        filled = result.fill.filled.reshape(n)
        fill_method = np.where(filled, result.fill.fill_method.reshape(n), np.array(None))
    else:
        filled, fill_method = np.zeros(n, dtype=bool), np.full(n, None)
    xyz = lifted.xyz.reshape(n, 3) if lifted is not None else np.full((n, 3), np.nan)
    lifted_rows = np.isfinite(xyz).all(axis=-1)
    return tables.from_columns("joints_3d", {
        "clip_id": clip.clip_id,
        "frame": np.repeat(np.arange(n_frames, dtype=np.int32), n_joints),
        "joint": np.asarray(clip.skeleton.joints, dtype=object)[joint_index],
        "joint_index": joint_index,
        "u": uv[:, 0],
        "v": uv[:, 1],
        "observed": clip.observed.reshape(n),
        "confidence": clip.confidence.reshape(n),
        "filled": filled,
        "fill_method": fill_method,
        "x": xyz[:, 0],
        "y": xyz[:, 1],
        "z": xyz[:, 2],
        "lift_method": (np.where(lifted_rows, lifted.method, np.array(None)) if lifted is not None
                        else np.full(n, None)),
        "scale": (np.repeat(lifted.scale, n_joints) if lifted is not None
                  else np.full(n, np.nan)),
        "sign_confidence": _flat(lifted.sign_confidence if lifted else None, n),
        "length_inconsistency": _flat(lifted.length_inconsistency if lifted else None, n),
    })


def _relative(path: str, inbox: Path) -> str:
    try:
        return Path(path).resolve().relative_to(inbox.resolve()).as_posix()
    except ValueError:
        return str(path)


def clip_tables(result: ClipResult, inbox: Path) -> dict[str, pa.Table]:
    """Every per-clip table of the result, ready for :meth:`handdb.store.database.Store.commit_clip`."""
    clip = result.clip
    out = {
        "clips": clips_table(result, [_relative(f, inbox) for f in clip.source_files]),
        "tracks_2d": tracks_2d_table(clip),
        "joints_3d": joints_3d_table(result),
    }
    truth = truth_3d_table(clip)
    if truth is not None:
        out["truth_3d"] = truth
    if result.bones is not None:
        out["bone_lengths"] = bone_lengths_table(clip.clip_id, clip.spec.subject, clip.skeleton,
                                                 result.bones)
    if result.validation is not None:
        out["validation_joint"] = result.validation
    if clip.markers is not None:
        out["markers_3d"] = markers_3d_table(clip.clip_id, clip.markers, clip.skeleton)
    if result.fit is not None:
        out["joint_angles"] = joint_angles_table(clip.clip_id, result.fit.model,
                                                 result.fit.poses)
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
        "gap_fill_method": [result.fill.method if result.fill else None],
        "lift_method": [result.lifted.method if result.lifted else None],
        "has_truth": [clip.truth is not None],
        "sidecar": [spec.raw],
        "usd_path": [result.usd_path],
        "handdb_version": [__version__],
    })


def ingest_xray(paths: list[Path], store: Store) -> tuple[pa.Table, list[Refusal]]:
    """Store the X-ray measurements of ``paths`` and recompute the joint ratios.

    Each file's measurements replace that file's partition of ``xray_measurements``;
    refused rows (an image lacking a segment of a finger, bad numbers...) become
    refusals and the rest goes on. ``joint_ratios`` is recomputed from every stored
    measurement and written when it changed.

    Returns
    -------
    ratios, refusals
        The ``joint_ratios`` table (empty when there is no X-ray data: bone lengths then
        fall back to the paper's Table 1) and the refused measurements.
    """
    from handdb.ingest.xray import read_xray
    from handdb.lengths.ratios import joint_ratios

    refusals: list[Refusal] = []
    for path in sorted(paths):
        measurements, errors = read_xray(path)
        refusals += [Refusal.from_error(error) for error in errors]
        key = path.name.removesuffix(xray.XRAY_SUFFIX)
        if store.read("xray_measurements", key) != tables.conform("xray_measurements",
                                                                  measurements):
            store.write("xray_measurements", key, measurements)
    ratios = joint_ratios(store.read_table("xray_measurements"))
    previous = store.read("joint_ratios", "joint_ratios")
    if previous is None or not previous.equals(tables.conform("joint_ratios", ratios)):
        store.write("joint_ratios", "joint_ratios", ratios)
    return ratios, refusals
