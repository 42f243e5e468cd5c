"""Build keys: what each stage's output depends on, so that only what changed is redone.

A clip passes the stages of :data:`STAGES`. Each stage's key hashes the keys of the stages
it reads from, the options that steer it and its algorithm's version: the ``VERSION`` of
the stage's package (``handdb.gapfill.VERSION``...), raised by hand when a change alters
what the stage computes. Editing a docstring or speeding a stage up changes no key; a new
gap-filling version changes the keys of gap filling and of every stage after it, not of
ingest or bone lengths. The contracts in ``schemas/`` (table columns, skeletons) enter every
key.

A marker clip has no gap filling or lifting of its own: its bone lengths, filled points and
positions all come from one model fit (:mod:`handdb.markers`), so those three stages share
the fit's key.
"""

from __future__ import annotations

import hashlib
import json
from functools import cache
from typing import Any

import pyarrow as pa

from handdb import export, gapfill, ingest, lengths, lifting, markers, validation
from handdb.build.options import BuildOptions
from handdb.paths import SCHEMAS_DIR

#: The stages of a clip, in the order they run.
STAGES: tuple[str, ...] = ("ingest", "lengths", "gap_fill", "lift", "validate", "export")

#: The stages a marker clip's model fit stands for.
MARKER_FIT_STAGES: tuple[str, ...] = ("lengths", "gap_fill", "lift")


def _digest(*parts: Any) -> str:
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()


@cache
def schemas_fingerprint() -> str:
    """SHA-256 over the contracts in ``schemas/``: names and bytes."""
    digest = hashlib.sha256()
    for path in sorted(p for p in SCHEMAS_DIR.rglob("*") if p.is_file()):
        digest.update(path.relative_to(SCHEMAS_DIR).as_posix().encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()


def table_hash(table: pa.Table) -> str:
    """SHA-256 of a table's rows, for keys that depend on a shared table (joint ratios)."""
    return hashlib.sha256(json.dumps(table.to_pylist(), sort_keys=True,
                                     default=str).encode()).hexdigest()


def stage_keys(content_hash: str, options: BuildOptions, ratios_hash: str, *,
               marker_clip: bool) -> dict[str, str]:
    """The key of every stage of a clip.

    Parameters
    ----------
    content_hash
        SHA-256 over the clip's input files.
    options
        The build's options.
    ratios_hash
        :func:`table_hash` of the joint ratios bone lengths are estimated with.
    marker_clip
        Whether the clip's data is 3D markers (fitted) rather than 2D tracks (lifted).

    Returns
    -------
    dict
        ``stage -> key`` for every stage of :data:`STAGES`, in order.
    """
    keys = {"ingest": _digest("ingest", ingest.VERSION, content_hash, schemas_fingerprint())}
    if marker_clip:
        fit = _digest("marker-fit", markers.VERSION, keys["ingest"])
        keys.update(dict.fromkeys(MARKER_FIT_STAGES, fit))
    else:
        keys["lengths"] = _digest("lengths", lengths.VERSION, keys["ingest"], ratios_hash)
        keys["gap_fill"] = _digest("gap_fill", gapfill.VERSION, keys["ingest"],
                                   options.gap_fill)
        keys["lift"] = _digest("lift", lifting.VERSION, keys["lengths"], keys["gap_fill"],
                               options.lift)
    keys["validate"] = _digest("validate", validation.VERSION, lifting.VERSION, keys["lift"],
                               list(options.compare))
    keys["export"] = _digest("export", export.VERSION, keys["lift"], options.export_usd)
    return keys


def build_key(keys: dict[str, str]) -> str:
    """One key for the whole clip: it changes when any stage's key does."""
    return _digest("clip", [keys[stage] for stage in STAGES])


def first_changed_stage(keys: dict[str, str], stored: dict[str, str] | None) -> str | None:
    """The first stage whose key differs from the stored one; ``None`` when none does."""
    for stage in STAGES:
        if stored is None or stored.get(stage) != keys[stage]:
            return stage
    return None
