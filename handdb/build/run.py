"""A whole build: plan, clips, quarantine and run record, without any orchestrator.

:class:`Build` holds one build under the database lock: :meth:`Build.begin` removes what an
interrupted build left, plans (:func:`~handdb.build.plan.plan_build`) and stores the X-ray
tables; every clip of :attr:`Build.todo` then goes through
:func:`~handdb.build.process.process_clip`, wherever that runs (this process's threads, a
Prefect task, a Dask worker), and its outcome comes back through :meth:`Build.record`;
:meth:`Build.finish` writes the ``quarantine`` table and the ``runs`` row and returns the
:class:`BuildSummary`. :func:`build_in_process` does all of it here, in a thread pool.
"""

from __future__ import annotations

import json
import time
import uuid
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

from threadpoolctl import threadpool_limits

from handdb import __version__
from handdb.build import progress
from handdb.build.context import BuildContext, StageFailed
from handdb.build.options import BuildOptions
from handdb.build.plan import BuildPlan, PlannedClip, plan_build
from handdb.build.window import IN_FLIGHT_PER_WORKER, sliding_window
from handdb.lazy import LazyFunction
from handdb.store import tables
from handdb.store.database import Store
from handdb.store.quarantine import Refusal
from handdb.validation.depth import clip_summary

if TYPE_CHECKING:
    from handdb.build.stages import ClipResult

#: BLAS threads per process during a build. Clips already run in parallel and the stages'
#: matrices are small (a few dozen columns), so threaded BLAS only makes the workers spin
#: against each other.
BLAS_THREADS = 1

#: Clips processed at once by default.
DEFAULT_WORKERS = 4

#: Name of the build in the ``runs`` table (and of its Prefect flow).
FLOW_NAME = "handdb-build"

#: :func:`~handdb.build.process.process_clip`, imported with every stage (numba, scipy)
#: when the first clip runs: a build with nothing to do never loads them.
process_clip = LazyFunction("handdb.build.process:process_clip")


@dataclass
class BuildSummary:
    """What a build did, for the command line, the artifacts and the ``runs`` table.

    ``flagged`` maps each flagged clip (one no hand could produce, or one the hand model
    completed where the input showed nothing) to the reasons; ``depth_ambiguous``
    each clip whose depth pose is not settled against its mirror image to the lifting's
    note (the clip is plausible: its ``clips`` row has ``depth_ambiguous`` true).
    ``flow_run_id`` and ``flow_run_url`` are the orchestrator's run of the build and its
    page, when an orchestrator ran it (``None`` for the local runner, and the URL ``None``
    too when no lasting server shows the run); ``changed`` says whether the build wrote
    anything besides its ``runs`` row.
    """

    run_id: str
    inbox: str
    db: str
    n_clips: int = 0
    n_frames: int = 0
    processed: list[str] = field(default_factory=list)
    unchanged: list[str] = field(default_factory=list)
    refusals: list[Refusal] = field(default_factory=list)
    failed: dict[str, str] = field(default_factory=dict)
    validation: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)
    flagged: dict[str, tuple[str, ...]] = field(default_factory=dict)
    depth_ambiguous: dict[str, str] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    removed_temporaries: int = 0
    repairs: tuple[str, ...] = ()
    flow_run_id: str | None = None
    flow_run_url: str | None = None
    changed: bool = False

    @property
    def ok(self) -> bool:
        """Every clip went through (refused input is not a failure of the build)."""
        return not self.failed


@dataclass
class Build:
    """One build of ``plan.inbox`` into ``plan.db``; hold the database lock around it."""

    plan: BuildPlan
    summary: BuildSummary
    started: datetime
    _clip_refusals: list[Refusal] = field(default_factory=list)
    _clock: float = field(default_factory=time.perf_counter)

    @classmethod
    def begin(cls, inbox: str, db: str, options: BuildOptions, *, run_id: str | None = None,
              plan: BuildPlan | None = None, flow_run_id: str | None = None,
              flow_run_url: str | None = None) -> Build:
        """Start a build: clean up after an interrupted one, plan, store the X-ray tables.

        The caller holds ``Store(db).lock()`` until :meth:`finish` returns. ``plan`` is a
        plan made a moment before for the same inbox, database and options (it is made
        here when not given). ``flow_run_id`` and ``flow_run_url`` name the orchestrator's
        run of this build and its page, for the ``runs`` row.
        """
        started = datetime.now(UTC)
        run_id = run_id or uuid.uuid4().hex[:12]
        store = Store(db)
        removed = store.remove_temporaries()
        clock = time.perf_counter()
        plan = plan or plan_build(inbox, db, options)
        for key, measurements in plan.xray.measurements.items():
            store.write("xray_measurements", key, measurements)
        if plan.xray.ratios_changed:
            store.write("joint_ratios", "joint_ratios", plan.xray.ratios)
        summary = BuildSummary(run_id=run_id, inbox=inbox, db=db, n_clips=len(plan.clips),
                               unchanged=[c.clip_id for c in plan.unchanged],
                               removed_temporaries=removed, repairs=plan.repairs,
                               flow_run_id=flow_run_id, flow_run_url=flow_run_url)
        summary.refusals.extend([*plan.refusals, *plan.xray.refusals])
        summary.timings["scan"] = time.perf_counter() - clock
        progress.expect(len(plan.clips))
        for clip in plan.unchanged:
            progress.finished(clip.clip_id, progress.UNCHANGED)
        return cls(plan=plan, summary=summary, started=started)

    @property
    def todo(self) -> tuple[PlannedClip, ...]:
        """The clips to process."""
        return self.plan.todo

    @property
    def context(self) -> BuildContext:
        """What :func:`~handdb.build.process.process_clip` needs besides the clip."""
        return BuildContext(inbox=self.plan.inbox, db=self.plan.db,
                            options=self.plan.options, ratios=self.plan.xray.ratios)

    def record(self, clip_id: str, outcome: ClipResult | Refusal | StageFailed) -> None:
        """Take one clip's outcome into the summary."""
        summary = self.summary
        if isinstance(outcome, StageFailed):
            summary.failed[clip_id] = str(outcome)
            progress.finished(clip_id, progress.FAILED)
        elif isinstance(outcome, Refusal):
            summary.refusals.append(outcome)
            self._clip_refusals.append(outcome)
            progress.finished(clip_id, progress.REFUSED)
        else:
            summary.processed.append(clip_id)
            summary.n_frames += outcome.clip.n_frames
            if outcome.validation is not None:
                summary.validation[clip_id] = clip_summary(outcome.validation)
            if outcome.verdict is not None and outcome.verdict.flagged:
                summary.flagged[clip_id] = outcome.verdict.reasons
            if outcome.lifted is not None and outcome.lifted.mirror_ambiguous:
                summary.depth_ambiguous[clip_id] = outcome.lifted.note
            progress.finished(clip_id, progress.DONE)

    def finish(self) -> BuildSummary:
        """Write the ``quarantine`` table (when it changed), the ``runs`` row and the stamps.

        The files of the clips processed are hashed again once settled (written
        :data:`~handdb.store.stamps.SETTLED_NS` before), so that the next build takes their
        digests from their stamps; a clip whose files changed since its commit keeps no
        entry, and the next build's plan finds it damaged.
        """
        store = Store(self.plan.db)
        stamps = dict(self.plan.stamps)
        for clip_id in self.summary.processed:
            stamps.update(store.checked_clip_files(clip_id, stamps)[1])
        store.keep_stamps(stamps)
        self.summary.timings["clips"] = time.perf_counter() - self._clock
        quarantine = self.plan.quarantine(store, self._clip_refusals)
        if quarantine is not None:
            store.write("quarantine", "quarantine", quarantine)
        xray = self.plan.xray
        self.summary.changed = bool(
            self.summary.processed or self.summary.removed_temporaries or quarantine is not None
            or xray.measurements or xray.ratios_changed)
        self._record_run(store)
        return self.summary

    def _record_run(self, store: Store) -> None:
        summary = self.summary
        params = {"inbox": summary.inbox, "db": summary.db, **self.plan.options.as_dict()}
        row = tables.from_columns("runs", {
            "run_id": [summary.run_id],
            "flow": [FLOW_NAME],
            "started_at": [self.started],
            "finished_at": [datetime.now(UTC)],
            "status": ["completed" if summary.ok else "failed"],
            "parameters": [json.dumps(params, sort_keys=True)],
            "handdb_version": [__version__],
            "n_clips": [summary.n_clips],
            "n_processed": [len(summary.processed)],
            "n_unchanged": [len(summary.unchanged)],
            "n_quarantined": [len(summary.refusals)],
            "n_failed": [len(summary.failed)],
            "timings": [json.dumps(summary.timings, sort_keys=True)],
            "flow_run_id": [summary.flow_run_id],
            "flow_run_url": [summary.flow_run_url],
        })
        store.write("runs", f"{self.started:%Y%m%dT%H%M%S}-{summary.run_id}", row)


def run_clip(item: PlannedClip, context: BuildContext) -> ClipResult | Refusal | StageFailed:
    """:func:`~handdb.build.process.process_clip`, with a stage failure as a value."""
    try:
        return process_clip(item, context)
    except StageFailed as failure:
        return failure


def build_in_process(inbox: str | Path, db: str, options: BuildOptions | None = None, *,
                     workers: int = DEFAULT_WORKERS, plan: BuildPlan | None = None
                     ) -> BuildSummary:
    """Build ``db`` from ``inbox`` in this process, ``workers`` clips at a time.

    A clip starts as soon as another finishes (:func:`~handdb.build.window.sliding_window`)
    and is recorded as it finishes, so a slow clip holds back no other.

    ``plan`` is a plan made a moment before (:func:`~handdb.build.plan.plan_build`).

    Raises
    ------
    UnknownNameError
        If an option names a method that does not exist.
    DatabaseLockedError
        If another build holds the database.
    """
    options = (options or BuildOptions()).check()
    with Store(db).lock(), threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        build = Build.begin(str(inbox), db, options, plan=plan)
        context = build.context
        with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
            finished = sliding_window(
                build.todo, max(1, workers) * IN_FLIGHT_PER_WORKER,
                lambda item: pool.submit(run_clip, item, context),
                lambda futures: next(as_completed(futures)))
            for item, future in finished:
                build.record(item.clip_id, future.result())
        return build.finish()


def summary_markdown(summary: BuildSummary) -> str:
    """A markdown report of a build."""
    lines = [
        f"# handdb build {summary.run_id}",
        "",
        f"- inbox: `{summary.inbox}`, database: `{summary.db}`",
        f"- clips in the inbox: {summary.n_clips}; processed {len(summary.processed)}, "
        f"unchanged {len(summary.unchanged)}, failed {len(summary.failed)}",
        f"- frames processed: {summary.n_frames}",
        f"- refused inputs (quarantine): {len(summary.refusals)}",
        f"- flagged: {len(summary.flagged)}",
        f"- depth ambiguous (the mirror image as likely): {len(summary.depth_ambiguous)}",
    ]
    if summary.repairs:
        lines += ["", "Damaged or missing in the database, written again:", ""]
        lines += [f"- {repair}" for repair in summary.repairs]
    if summary.refusals:
        lines += ["", "| file | line | field | reason |", "|---|---|---|---|"]
        lines += [f"| {r.file} | {r.line or ''} | {r.field or ''} | {r.reason} |"
                  for r in summary.refusals]
    if summary.flagged:
        lines += ["", "Flagged clips: stored, but no human hand could produce them:", "",
                  "| clip | why |", "|---|---|"]
        lines += [f"| {clip_id} | {'; '.join(reasons)} |"
                  for clip_id, reasons in sorted(summary.flagged.items())]
    if summary.depth_ambiguous:
        lines += ["", "Depth-ambiguous clips: stored, plausible, but their depths may be the "
                  "mirror image of the hand's:", "", "| clip | why |", "|---|---|"]
        lines += [f"| {clip_id} | {note} |"
                  for clip_id, note in sorted(summary.depth_ambiguous.items())]
    if summary.validation:
        lines += ["", "Depth against ground truth, processed clips (clip units):", "",
                  "| clip | method | mean abs dZ | sign accuracy | MPJPE |",
                  "|---|---|---:|---:|---:|"]
        lines += [f"| {clip_id} | {method} | {f['dz_mean']:.3g} | {f['sign_accuracy']:.1%} | "
                  f"{f['mpjpe']:.3g} |"
                  for clip_id, methods in sorted(summary.validation.items())
                  for method, f in sorted(methods.items(), key=lambda kv: kv[1]["dz_mean"])]
    if summary.failed:
        lines += ["", "| failed clip | error |", "|---|---|"]
        lines += [f"| {c} | {e} |" for c, e in summary.failed.items()]
    return "\n".join(lines)
