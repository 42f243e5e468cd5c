"""The stages of one clip as plain functions: what the build does to a clip.

In order: ingest (read and validate the clip's files) → bone lengths → gap fill → lift
(a marker clip: the model fit, which stands for the three) → validate → export. Each stage
takes a :class:`ClipResult` and returns a new one; a stage that cannot use the clip's input
raises :class:`ClipRefused`, naming the sidecar key to change when there is one.
:func:`handdb.build.clip.process_clip` runs them and commits the clip.
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from handdb.build.options import BuildOptions
from handdb.clip import Clip, finite_points
from handdb.errors import (
    ClipDataError,
    HanddbError,
    InputError,
    ParameterError,
    SkeletonError,
    StageError,
    UnknownNameError,
)
from handdb.gapfill import DEFAULT_METHOD as DEFAULT_GAP_FILL
from handdb.gapfill import FillResult, fill_gaps
from handdb.gapfill.caveats import caveat_rows, fill_caveats
from handdb.ingest import ClipEntry, load_clip
from handdb.lengths.bone_lengths import BoneLengths, clip_bone_lengths
from handdb.lifting import DEFAULT_METHOD as DEFAULT_LIFT
from handdb.lifting import LiftResult, lift
from handdb.markers.fit import (
    MarkerFit,
    fit_markers,
    fit_positions,
    fitted_bone_lengths,
    joint_motion,
)
from handdb.store.database import Store
from handdb.validation.depth import comparison_chart, markdown_summary, validation_table
from handdb.validation.plausibility import Verdict, assess

#: Lifting methods compared against ground truth for every 2D clip that has it.
VALIDATED_METHODS: tuple[str, ...] = ("thesis", "thesis-nocheck", DEFAULT_LIFT)

#: Folders of the database that hold files other than tables.
USD_DIR, REPORTS_DIR = "usd", "reports"


class ClipRefused(HanddbError):
    """A stage cannot use the clip's input; the clip goes to the ``quarantine`` table.

    Parameters
    ----------
    error
        What went wrong; an :class:`~handdb.errors.InputError` names its own file and field.
    field
        The sidecar key the user can change to fix it, or ``None`` (never a key the
        sidecar does not have).
    """

    def __init__(self, error: Exception, field: str | None = None) -> None:
        self.error = error
        self.field = field
        super().__init__(str(error))


@dataclass(frozen=True)
class ClipResult:
    """Everything the stages produced for one clip, ready to be committed.

    ``keys`` are the clip's stage keys (:func:`handdb.build.keys.stage_keys`).
    """

    clip: Clip
    keys: dict[str, str] = field(default_factory=dict)
    bones: BoneLengths | None = None
    fill: FillResult | None = None
    lifted: LiftResult | None = None
    fit: MarkerFit | None = None
    validation: pa.Table | None = None
    report: str | None = None
    verdict: Verdict | None = None
    usd_path: str | None = None

    @property
    def uv(self) -> np.ndarray:
        """``(T, J, 2) float64`` pixels used for lifting: observed or filled, else NaN."""
        if self.fill is not None:
            return self.fill.uv
        return np.where(self.clip.observed[..., None], self.clip.uv, np.nan)


def _needs(value: Any, stage: str, result: ClipResult) -> Any:
    """Return what an earlier stage produced, or raise if that stage has not run."""
    if value is None:
        raise StageError(f"clip '{result.clip.clip_id}': the {stage} stage has not run")
    return value


def _method(choice: str | None, sidecar: dict[str, Any], default: str) -> tuple[str, dict]:
    """The method to run and its parameters: the build's override, the sidecar, the default."""
    if choice is not None:
        return choice, {}
    params = {k: v for k, v in sidecar.items() if k != "method"}
    return sidecar.get("method", default), params


#: What a method's choice or parameters can be wrong by: an unknown name, parameters the
#: method does not take, values it cannot use.
METHOD_ERRORS = (UnknownNameError, TypeError, ParameterError)


def _method_refusal(error: Exception, clip: Clip, key: str) -> ClipRefused:
    """Refuse a clip for a method's choice or parameters, or for what its data lacks.

    ``key`` (``gap_fill``, ``lift``) is blamed only when the sidecar has it.
    """
    if isinstance(error, METHOD_ERRORS):
        given = getattr(clip.spec, key)
        return ClipRefused(error, key if given else None)
    return ClipRefused(error)


def ingest(entry: ClipEntry, content_hash: str | None = None) -> Clip:
    """Read and validate the clip's files.

    Raises
    ------
    ClipRefused
        With the :class:`~handdb.errors.InputError` that names the file, line and field.
    """
    try:
        return load_clip(entry, content_hash=content_hash)
    except InputError as error:
        raise ClipRefused(error) from None


def resolve_bone_lengths(result: ClipResult, ratios: pa.Table | None) -> ClipResult:
    """Give every bone of a 2D clip a length, with its source and uncertainty."""
    if ratios is not None and ratios.num_rows == 0:
        ratios = None
    return replace(result, bones=clip_bone_lengths(result.clip, ratios))


def fill(result: ClipResult, options: BuildOptions) -> ClipResult:
    """Fill the 2D clip's missing points with the chosen gap-filling method.

    A clip of independent images (``clip.sampling``) is filled image by image.
    """
    clip = result.clip
    method, params = _method(options.gap_fill, clip.spec.gap_fill, DEFAULT_GAP_FILL)
    try:
        filled = fill_gaps(clip.uv, clip.observed, clip.skeleton, method,
                           sampling=clip.sampling, **params)
    except (*METHOD_ERRORS, ClipDataError) as error:
        raise _method_refusal(error, clip, "gap_fill") from None
    return replace(result, fill=filled)


def lift_clip(result: ClipResult, options: BuildOptions) -> ClipResult:
    """Lift the filled 2D points to 3D with the chosen method.

    A clip of independent images (``clip.sampling``) is lifted image by image.
    """
    clip = result.clip
    method, params = _method(options.lift, clip.spec.lift, DEFAULT_LIFT)
    bones = _needs(result.bones, "bone lengths", result)
    try:
        lifted = lift(result.uv, clip.skeleton, bones.lengths, clip.spec.camera,
                      method=method, hand=clip.spec.hand, sampling=clip.sampling, **params)
    except (*METHOD_ERRORS, ClipDataError) as error:
        raise _method_refusal(error, clip, "lift") from None
    return replace(result, lifted=lifted)


def fit_marker_clip(result: ClipResult) -> ClipResult:
    """Fit the kinematic hand model to the clip's 3D markers (Zhao et al. 2012).

    Without bone lengths in the sidecar, the subject is calibrated from the clip first.
    The sidecar's ``lift`` parameters go to :func:`handdb.markers.fit.fit_markers`.
    """
    clip, spec = result.clip, result.clip.spec
    markers = _needs(clip.markers, "marker ingest", result)
    params = {k: v for k, v in spec.lift.items() if k != "method"}
    try:
        fit = fit_markers(markers, hand=spec.hand, units=spec.units, skeleton=spec.skeleton,
                          bone_lengths=spec.bone_lengths or None, **params)
    except SkeletonError as error:
        raise ClipRefused(ValueError(f"the hand model cannot fit markers on '{spec.skeleton}': "
                                     f"{error}"), "skeleton") from None
    except (*METHOD_ERRORS, ClipDataError) as error:
        raise _method_refusal(error, clip, "lift") from None
    return replace(result, fit=fit, lifted=fit_positions(fit),
                   bones=fitted_bone_lengths(fit, spec))


def validate(result: ClipResult, options: BuildOptions) -> ClipResult:
    """Check the result against what hands can be; compare it with the ground truth, if any.

    The plausibility gate (:func:`handdb.validation.plausibility.assess`) runs on every
    clip; what gap filling could not know (:func:`handdb.gapfill.caveats.fill_caveats`)
    joins its reasons, and the rows it is about
    (:func:`handdb.gapfill.caveats.caveat_rows`) its rows. The lifting
    methods are compared on clips with ground truth.
    """
    clip = result.clip
    lifted = _needs(result.lifted, "lift", result)
    bones = _needs(result.bones, "bone lengths", result)
    residual = result.fit.residual if result.fit is not None else None
    verdict = assess(clip.skeleton, clip.spec.units, clip.spec.hand, bones.lengths,
                     lifted.xyz, residual, labelled=clip.markers,
                     sampling=clip.sampling)
    if result.fill is not None:
        verdict = Verdict(reasons=(*fill_caveats(result.fill, clip.skeleton), *verdict.reasons),
                          rows=verdict.rows | caveat_rows(result.fill))
    result = replace(result, verdict=verdict)
    if clip.truth is None:
        return result
    estimates: dict[str, LiftResult | np.ndarray] = {lifted.method: lifted}
    methods = (*VALIDATED_METHODS, *options.compare) if clip.markers is None else ()
    for method in methods:
        if method not in estimates:
            estimates[method] = lift(result.uv, clip.skeleton, bones.lengths,
                                     clip.spec.camera, method=method, hand=clip.spec.hand,
                                     sampling=clip.sampling)
    table = validation_table(clip.clip_id, clip.truth, estimates, clip.skeleton, clip.spec.units)
    return replace(result, validation=table, report=markdown_summary(clip.clip_id, table))


def _put(store: Store, local: Path, *parts: str) -> str:
    """Move a local file into the database; return its path relative to the database.

    Within one local filesystem the move is a rename (atomic); across filesystems it is a
    copy. A file cut short by a killed build belongs to an uncommitted clip, which the
    next build writes again.
    """
    store.makedirs(*parts[:-1])
    target = store.checked(store.path(*parts))
    if store.is_local:
        shutil.move(local, target)
    else:
        store.fs.put_file(str(local), target)
    return "/".join(parts)


def _flag_unplaced(result: ClipResult, unplaced: np.ndarray) -> ClipResult:
    """``result`` with its joints that have no 3D position, ``(T, J) bool``, flagged and said."""
    frames = np.flatnonzero(unplaced.any(axis=1))
    missing = (f"{unplaced.sum()} joint positions in {len(frames)} frames (from frame "
               f"{frames[0]}) could not be placed")
    placed = np.flatnonzero(~unplaced.any(axis=1))
    if len(placed):
        reason = (f"USD animates frames {placed[0]}-{placed[-1]}: {missing}, and USD holds "
                  "the nearest keyed pose there (interpolates it inside that span)")
    else:
        reason = (f"no USD or preview written: {missing}; fill them ('gap_fill') or cut "
                  "those frames from the track")
    verdict = result.verdict or Verdict(reasons=(), rows=np.zeros_like(unplaced))
    return replace(result, verdict=Verdict(reasons=(*verdict.reasons, reason),
                                           rows=verdict.rows | unplaced))


def export(result: ClipResult, store: Store, options: BuildOptions) -> ClipResult:
    """Write the clip's USD animation, preview thumbnail and validation chart into the database.

    A clip with joints that could not be lifted (a detector's empty first or last frames)
    says so: the reason joins its flag reasons, the frames and joints its flagged rows. Its
    USD animates the frames that place every joint (:mod:`handdb.export.usd`); only a clip
    with no such frame is not exported (``usd_path`` stays null).
    """
    clip = result.clip
    lifted = _needs(result.lifted, "lift", result)
    bones = _needs(result.bones, "bone lengths", result)
    if not options.export_usd:
        return result
    unplaced = ~finite_points(lifted.xyz)                       # (T, J)
    if unplaced.any():
        result = _flag_unplaced(result, unplaced)
        if unplaced.any(axis=1).all():
            return result
    # USD takes a second to import: a build with nothing to export skips it
    from handdb.export.thumbnail import write_thumbnail_png
    from handdb.export.usd import export_clip_usd

    spec = clip.spec
    with tempfile.TemporaryDirectory() as scratch:
        scratch_dir = Path(scratch)
        rotations = joint_motion(result.fit, spec.units) if result.fit is not None else None
        usd = export_clip_usd(scratch_dir / f"{clip.clip_id}.usd", clip_id=clip.clip_id,
                              skeleton=clip.skeleton, xyz=lifted.xyz,
                              bone_lengths=bones.lengths, fps=spec.fps,
                              units=spec.units, hand=spec.hand, rotations=rotations)
        usd_path = _put(store, usd, USD_DIR, usd.name)
        # the labelled sheet costs 15 times the thumbnail: `handdb preview` draws it
        preview = write_thumbnail_png(
            scratch_dir / "preview.png", skeleton=clip.skeleton, xyz=lifted.xyz,
            filled=None if result.fill is None else result.fill.filled, truth=clip.truth)
        _put(store, preview, REPORTS_DIR, clip.clip_id, "preview.png")
        if result.validation is not None:
            chart = scratch_dir / "depth.png"
            chart.write_bytes(comparison_chart(clip.clip_id, result.validation, clip.skeleton))
            _put(store, chart, REPORTS_DIR, clip.clip_id, "depth.png")
    return replace(result, usd_path=usd_path)
