"""Clips with complete tracks for the gap-filling evaluation, and where its results go.

Only a clip whose every point is observed can be scored: its points are hidden on purpose
and the fill compared with them. Such clips come from three places, each named by a small
*source* that loads the clip (a :class:`~handdb.clip.Clip`) when asked, so that an
orchestrator can hand sources to its tasks:

* :class:`SyntheticSource`: a synthesized clip (``synthetic-<motion>-seed<seed>``);
* :class:`DatabaseSource`: a clip of a handdb database (:func:`~handdb.store.clips.stored_clip`);
* :class:`InboxSource`: a clip of an inbox, read by the inbox readers.

:func:`evaluate_source` scores one source's clip and stores its ``gapfill_eval`` rows
(partition per clip) and its chart (``<db>/reports/<clip_id>/gapfill.png``);
:func:`evaluate_sources` does every source in this process, and :func:`summarise` gathers
the results into an :class:`EvalSummary`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pyarrow as pa

from handdb.clip import Clip
from handdb.errors import InputError, StoreError
from handdb.gapfill.evaluate import (
    OCCLUSION_MASK,
    Evaluation,
    evaluate_clip,
    plot_masks,
    rmse_markdown,
)
from handdb.gapfill.methods import DEFAULT_METHOD, METHODS, THESIS
from handdb.ingest.inbox import ClipEntry, load_clip
from handdb.store import tables
from handdb.store.clips import stored_clip
from handdb.store.database import Store

#: Table of the evaluation's rows.
EVAL_TABLE = "gapfill_eval"
#: Folder of per-clip reports in a database, and the evaluation chart's file name.
REPORTS = "reports"
CHART = "gapfill.png"


def _complete(clip: Clip) -> Clip | None:
    """``clip`` with its truth dropped when incomplete, or ``None`` if a point is unobserved."""
    if not clip.observed.all():
        return None
    if clip.truth is not None and not np.isfinite(clip.truth).all():
        return replace(clip, truth=None)
    return clip


@dataclass(frozen=True)
class SyntheticSource:
    """A synthesized clip (see :func:`handdb.synthetic.clips.synthesize_clip`)."""

    motion: str
    n_frames: int
    seed: int
    skeleton: str = "mediapipe21"

    @property
    def clip_id(self) -> str:
        """``synthetic-<motion>-seed<seed>``."""
        return f"synthetic-{self.motion}-seed{self.seed}"

    def load(self) -> Clip | None:
        """Synthesize the clip."""
        from handdb.synthetic.clips import synthesize_clip

        clip = synthesize_clip(self.motion, self.n_frames, skeleton=self.skeleton, seed=self.seed)
        return clip.as_clip(self.clip_id)


@dataclass(frozen=True)
class DatabaseSource:
    """A clip of the database at ``db``."""

    db: str
    clip_id: str

    def load(self) -> Clip | None:
        """Read the clip back; ``None`` when a point is not observed or it is not stored."""
        try:
            return _complete(stored_clip(Store(self.db), self.clip_id))
        except StoreError:
            return None


@dataclass(frozen=True)
class InboxSource:
    """A clip of an inbox."""

    entry: ClipEntry

    @property
    def clip_id(self) -> str:
        """The inbox clip's id."""
        return self.entry.clip_id

    def load(self) -> Clip | None:
        """Read the clip; ``None`` when a point is not observed or the files are refused."""
        try:
            return _complete(load_clip(self.entry))
        except InputError:
            return None


ClipSource = SyntheticSource | DatabaseSource | InboxSource


def database_sources(db: str) -> list[DatabaseSource]:
    """List the database's clips whose points were all observed (by ``clips``).

    A clip's ``n_observed`` must equal its frames times joints; :meth:`DatabaseSource.load`
    checks the points themselves.
    """
    clips = Store(db).read_table("clips").to_pydict()
    return [
        DatabaseSource(db, clip_id)
        for clip_id, seen, frames, joints in zip(
            clips["clip_id"], clips["n_observed"], clips["n_frames"], clips["n_joints"],
            strict=True)
        if seen == frames * joints
    ]


def chart_path(store: Store, clip_id: str) -> str:
    """Where the clip's gap-filling chart goes in the database."""
    return store.path(REPORTS, clip_id, CHART)


def store_evaluation(
    store: Store, clip: Clip, evaluation: Evaluation, methods: Sequence[str]
) -> str:
    """Write a clip's ``gapfill_eval`` rows and its chart (one panel per mask) into ``store``.

    The chart, like the thesis's Figure 4.6, draws the thesis's methods among ``methods``
    and the default last, on top (all of ``methods`` when none of those was scored).

    Returns
    -------
    str
        The chart's path on the store's filesystem.
    """
    store.write(EVAL_TABLE, clip.clip_id, evaluation.table)
    charted = [m for m in methods if METHODS[m].family == THESIS]
    charted += [DEFAULT_METHOD] if DEFAULT_METHOD in methods else []
    store.makedirs(REPORTS, clip.clip_id)
    path = store.checked(chart_path(store, clip.clip_id))
    with store.fs.open(path, "wb") as fh:
        plot_masks(evaluation, clip.skeleton, fh, methods=charted or list(methods),
                   title=f"{clip.clip_id}: gap-filling error per frame")
    return path


@dataclass
class EvalSummary:
    """What an evaluation did: the rows of every clip scored, and the clips skipped."""

    table: pa.Table
    charts: dict[str, str] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)


def evaluate_source(source: ClipSource, db: str, masks: Sequence[str],
                    methods: Sequence[str], seed: int) -> tuple[pa.Table, str] | None:
    """Score one source's clip and store its rows and chart; ``None`` if it cannot be scored.

    The occlusion mask needs the clip's 3D truth and is left out for clips without it.
    """
    clip = source.load()
    if clip is None:
        return None
    usable = [m for m in masks if m != OCCLUSION_MASK or clip.truth is not None]
    evaluation = evaluate_clip(clip.clip_id, clip.uv, clip.skeleton, masks=usable,
                               methods=methods, xyz=clip.truth, seed=seed)
    chart = store_evaluation(Store(db), clip, evaluation, methods)
    return evaluation.table, chart


def summarise(sources: Sequence[ClipSource],
              results: Sequence[tuple[pa.Table, str] | None]) -> EvalSummary:
    """Gather :func:`evaluate_source`'s results, in the sources' order."""
    done = [result for result in results if result is not None]
    return EvalSummary(
        table=pa.concat_tables([t for t, _ in done]) if done else tables.empty(EVAL_TABLE),
        charts={s.clip_id: r[1] for s, r in zip(sources, results, strict=True) if r},
        skipped=[s.clip_id for s, r in zip(sources, results, strict=True) if r is None],
    )


def evaluate_sources(sources: Sequence[ClipSource], db: str, masks: Sequence[str],
                     methods: Sequence[str], seed: int = 0) -> EvalSummary:
    """Score every source's clip in this process, one after the other."""
    return summarise(sources, [evaluate_source(s, db, masks, methods, seed) for s in sources])


def summary_markdown(summary: EvalSummary) -> str:
    """A markdown report: the pooled RMSE table and the clips scored or skipped."""
    lines = ["# Gap filling: RMSE over hidden points, pixels", ""]
    if summary.table.num_rows:
        lines += [rmse_markdown(summary.table), ""]
    lines.append(f"Clips scored: {', '.join(summary.charts) or 'none'}.")
    if summary.skipped:
        lines.append(f"Skipped (incomplete tracks or refused files): "
                     f"{', '.join(summary.skipped)}.")
    return "\n".join(lines)
