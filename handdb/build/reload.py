"""What earlier builds stored for a clip, read back as the stages' outputs.

A rebuild starts at the first stage whose key changed (:mod:`handdb.build.keys`); the
stages before it are not run again but read from the tables they wrote: the ingested
tracks from ``tracks_2d``, ``truth_3d`` and ``markers_3d`` (with the clip's sidecar, whose
bytes the ingest key covers), bone lengths from ``bone_lengths``, the filled points and the
lifted joints from ``joints_3d`` (the lifting's doubt about the depth pose from ``clips``),
the comparison from ``validation_joint``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pyarrow as pa

from handdb.build.keys import STAGES
from handdb.build.stages import ClipResult
from handdb.clip import Clip
from handdb.gapfill import FillResult
from handdb.ingest.inbox import ClipEntry
from handdb.lengths.bone_lengths import BoneLengths
from handdb.lifting import LiftResult
from handdb.store.clips import read_partition, scatter, stored_clip
from handdb.store.database import Store
from handdb.validation.depth import markdown_summary
from handdb.validation.plausibility import Verdict


def _clip(store: Store, entry: ClipEntry, content_hash: str) -> Clip:
    """The clip as ingest made it, from the stored rows and the clip's sidecar."""
    clip = stored_clip(store, entry.clip_id, sidecar=entry.sidecar, content_hash=content_hash)
    return replace(clip, source_files=tuple(str(path) for path in entry.paths))


def stored_bone_lengths(store: Store, clip: Clip) -> BoneLengths:
    """The clip's stored ``bone_lengths`` rows as :class:`BoneLengths`."""
    skeleton = clip.skeleton
    rows = read_partition(store, "bone_lengths", clip.clip_id).to_pylist()
    lengths = np.full(skeleton.n_joints, np.nan)
    residuals = np.full(skeleton.n_joints, np.nan)
    uncertainty = np.full(skeleton.n_joints, np.nan)
    n_frames = np.zeros(skeleton.n_joints, dtype=np.int64)
    sources: list[str | None] = [None] * skeleton.n_joints
    details: list[str | None] = [None] * skeleton.n_joints
    for row in rows:
        j = skeleton.index(row["bone"])
        lengths[j] = row["length"]
        residuals[j] = np.nan if row["residual"] is None else row["residual"]
        uncertainty[j] = np.nan if row["uncertainty"] is None else row["uncertainty"]
        n_frames[j] = row["n_frames"] or 0
        sources[j], details[j] = row["source"], row["detail"]
    return BoneLengths(skeleton=skeleton, units=rows[0]["units"], lengths=lengths,
                       sources=tuple(sources), details=tuple(details), residuals=residuals,
                       n_frames=n_frames, uncertainty=uncertainty)


def _stored_fill(joints: pa.Table, clip: Clip, method: str) -> FillResult:
    shape = clip.observed.shape
    filled = joints.column("filled").to_numpy(zero_copy_only=False).reshape(shape)
    labels = np.array(joints.column("fill_method").fill_null("").to_pylist(),
                      dtype=str).reshape(shape)
    uv = scatter(joints, shape + (2,), ("u", "v"))
    return FillResult(uv=uv, filled=filled, method=method, fill_method=labels, flags=())


def _stored_lift(joints: pa.Table, clip: Clip, row: dict[str, Any]) -> LiftResult:
    """The lift from ``joints_3d``; its doubt about the depth pose from the ``clips`` row."""
    shape = clip.observed.shape
    per_joint = {name: joints.column(name).to_numpy(zero_copy_only=False).reshape(shape)
                 for name in ("scale", "sign_confidence", "length_inconsistency")}
    return LiftResult(xyz=scatter(joints, shape + (3,), ("x", "y", "z")),
                      sign_confidence=per_joint["sign_confidence"],
                      length_inconsistency=per_joint["length_inconsistency"],
                      scale=per_joint["scale"][:, 0], method=row["lift_method"],
                      mirror_ambiguous=bool(row["depth_ambiguous"]),
                      mirror_log_odds=row["depth_log_odds"], note=row["lift_note"] or "")


def resume(store: Store, entry: ClipEntry, content_hash: str, keys: dict[str, str],
           start: str) -> ClipResult:
    """The outputs of every stage before ``start``, read from the store.

    Parameters
    ----------
    store
        The database the clip was committed to.
    entry, content_hash
        The clip's inbox entries and their hash (unchanged since the commit).
    keys
        The clip's stage keys for this build.
    start
        The first stage to run (a stage after ``ingest``).
    """
    done = STAGES[: STAGES.index(start)]
    clip = _clip(store, entry, content_hash)
    row = read_partition(store, "clips", clip.clip_id).to_pylist()[0]
    joints = (read_partition(store, "joints_3d", clip.clip_id)
              if {"gap_fill", "lift", "validate"} & set(done) else None)
    validation = (read_partition(store, "validation_joint", clip.clip_id)
                  if "validate" in done and row["has_truth"] else None)
    verdict = (Verdict(reasons=tuple(row["flag_reasons"]),
                       rows=joints.column("flagged").to_numpy(zero_copy_only=False).reshape(
                           clip.observed.shape))
               if "validate" in done and joints is not None else None)
    return ClipResult(
        clip=clip, keys=keys,
        bones=stored_bone_lengths(store, clip) if "lengths" in done else None,
        fill=_stored_fill(joints, clip, row["gap_fill_method"]) if "gap_fill" in done else None,
        lifted=_stored_lift(joints, clip, row) if "lift" in done else None,
        validation=validation,
        report=markdown_summary(clip.clip_id, validation) if validation is not None else None,
        verdict=verdict,
    )
