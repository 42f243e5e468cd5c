"""The build flow: inbox → database, one chain of tasks per clip.

The inbox's X-ray files are read first and the joint ratios recomputed (a task); then
each clip passes ingest → bone lengths → gap fill → lift → validate → export → commit,
each stage a task that calls ``handdb.build.stages``. Clips whose build key is already in the
database are skipped (the database is the cache). Chains are submitted in windows of a few
clips so memory is bounded by the largest clips in flight, not by the database.
Inputs the library refuses (bad files, no bone lengths) travel down the chain as a
:class:`~handdb.store.quarantine.Refusal` and end in the ``quarantine`` table; the other clips go on.
"""

from __future__ import annotations

import contextlib
import json
import re
import time
import uuid
from dataclasses import asdict, dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, cast

import pyarrow as pa
from prefect import flow, get_run_logger, task
from prefect.artifacts import create_markdown_artifact
from prefect.cache_policies import NO_CACHE
from prefect.futures import PrefectFuture, wait
from prefect.task_runners import TaskRunner, ThreadPoolTaskRunner
from threadpoolctl import threadpool_limits

from handdb_flows.settings import shared_api
from handdb import __version__
from handdb.build import progress
from handdb.build import stages as pipeline
from handdb.ingest import InboxScan, content_hash, discover
from handdb.lengths.ratios import ratios_markdown
from handdb.store import tables
from handdb.store.database import Store
from handdb.store.quarantine import Refusal, quarantine_table
from handdb.validation.depth import clip_summary

#: Clips whose task chains run at once; bounds memory and the thread pool's queue.
WINDOW_PER_WORKER = 2
DEFAULT_WORKERS = 4
#: BLAS threads per process during a build. Clips already run in parallel and the stages'
#: matrices are small (a few dozen columns), so threaded BLAS only made the workers spin
#: against each other: gap filling ran 6x slower with OpenBLAS's default thread count.
BLAS_THREADS = 1


def _retry_on_io(task: Any, task_run: Any, state: Any) -> bool:
    """Retry a task only for I/O errors, never for refused input."""
    try:
        state.result()
    except OSError:
        return True
    except Exception:  # noqa: BLE001 - any other failure is final
        return False
    return False


IO_RETRIES: dict[str, Any] = {"retries": 2, "retry_delay_seconds": 1,
                             "retry_condition_fn": _retry_on_io}


@dataclass
class BuildSummary:
    """What a build did, for the CLI and the ``runs`` table."""

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
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every clip went through (refused input is not a failure of the build)."""
        return not self.failed


@task(name="scan-inbox", cache_policy=NO_CACHE, **IO_RETRIES)
def scan_inbox(inbox: str) -> InboxScan:
    """Find the clips and refused entries in the inbox."""
    return discover(Path(inbox))


@task(name="xray-ratios", cache_policy=NO_CACHE, **IO_RETRIES)
def xray_ratios(paths: list[Path], db: str) -> tuple[pa.Table, list[Refusal]]:
    """Store the inbox's X-ray measurements, recompute the joint ratios, publish them."""
    ratios, refusals = pipeline.ingest_xray(paths, Store(db))
    if ratios.num_rows:
        create_markdown_artifact(markdown=ratios_markdown(ratios), key="joint-ratios",
                                 description="joint ratios from X-ray measurements")
    return ratios, refusals


Outcome = pipeline.ClipResult | Refusal


@task(name="ingest", task_run_name="ingest {clip_id}", cache_policy=NO_CACHE, **IO_RETRIES)
def ingest(entry: Any, clip_id: str, key: str) -> Outcome:
    """Read and validate one clip's files."""
    outcome = pipeline.ingest(entry, key)
    progress.advance(clip_id, "ingest")
    return outcome


@task(name="bone-lengths", task_run_name="bone lengths {clip_id}", cache_policy=NO_CACHE)
def bone_lengths(result: Outcome, clip_id: str, ratios: pa.Table | None) -> Outcome:
    """Give every bone of the clip a length."""
    return pipeline.resolve_bone_lengths(result, ratios)


@task(name="gap-fill", task_run_name="gap fill {clip_id}", cache_policy=NO_CACHE)
def gap_fill(result: Outcome, clip_id: str, options: pipeline.BuildOptions) -> Outcome:
    """Fill the clip's missing 2D points."""
    return pipeline.fill(result, options)


@task(name="lift", task_run_name="lift {clip_id}", cache_policy=NO_CACHE)
def lift(result: Outcome, clip_id: str, options: pipeline.BuildOptions) -> Outcome:
    """Give every joint of every frame its depth."""
    return pipeline.lift_clip(result, options)


@task(name="validate", task_run_name="validate {clip_id}", cache_policy=NO_CACHE)
def validate(result: Outcome, clip_id: str, options: pipeline.BuildOptions) -> Outcome:
    """Compare lifting methods against ground truth; publish the comparison."""
    result = pipeline.validate(result, options)
    if isinstance(result, pipeline.ClipResult) and result.report is not None:
        create_markdown_artifact(markdown=result.report, key=artifact_key("validation", clip_id),
                                 description=f"depth validation of clip {clip_id}")
    return result


@task(name="export", task_run_name="export {clip_id}", cache_policy=NO_CACHE, **IO_RETRIES)
def export(result: Outcome, clip_id: str, db: str, options: pipeline.BuildOptions) -> Outcome:
    """Write the clip's USD animation and preview images."""
    return pipeline.export(result, Store(db), options)


@task(name="commit", task_run_name="commit {clip_id}", cache_policy=NO_CACHE, **IO_RETRIES)
def commit(result: pipeline.ClipResult | Refusal, clip_id: str, db: str, inbox: str
           ) -> pipeline.ClipResult | Refusal:
    """Write the clip's tables, its ``clips`` row last."""
    if isinstance(result, Refusal):
        return result
    Store(db).commit_clip(result.clip.clip_id, pipeline.clip_tables(result, Path(inbox)))
    progress.advance(result.clip.clip_id, "commit")
    return result


def artifact_key(kind: str, clip_id: str) -> str:
    """Return a Prefect artifact key (lowercase letters, digits, dashes) for a clip."""
    return re.sub(r"[^a-z0-9-]+", "-", f"{kind}-{clip_id}".lower()).strip("-")


def _run_clip_chain(entry: Any, key: str, db: str, inbox: str, ratios: pa.Table,
                    options: pipeline.BuildOptions) -> dict[str, PrefectFuture]:
    """Submit one clip's stages; return their futures by stage name, in order (commit last)."""
    clip_id = entry.clip_id
    # Any: each stage takes the previous stage's future, which Prefect resolves before the
    # task runs, but Task.submit's types admit only the resolved value.
    chain: dict[str, Any] = {"ingest": ingest.submit(entry, clip_id, key)}
    chain["bone-lengths"] = bone_lengths.submit(chain["ingest"], clip_id, ratios)
    chain["gap-fill"] = gap_fill.submit(chain["bone-lengths"], clip_id, options)
    chain["lift"] = lift.submit(chain["gap-fill"], clip_id, options)
    chain["validate"] = validate.submit(chain["lift"], clip_id, options)
    chain["export"] = export.submit(chain["validate"], clip_id, db, options)
    chain["commit"] = commit.submit(chain["export"], clip_id, db, inbox)
    return chain


def _chain_failure(chain: dict[str, PrefectFuture]) -> str | None:
    """Why a clip's chain did not complete (its first failed stage), or ``None``."""
    if chain["commit"].state.is_completed():
        return None
    stage, future = next((stage, future) for stage, future in chain.items()
                         if not future.state.is_completed())
    return f"{stage}: {future.state.message or future.state.name}"


def task_runner(runner: str = "thread", workers: int = DEFAULT_WORKERS,
                dask_address: str | None = None) -> Any:
    """Choose the task runner for per-clip tasks: a bounded thread pool, or Dask.

    ``dask`` starts a local Dask cluster of ``workers`` processes unless ``dask_address``
    names an existing scheduler.
    """
    if runner == "thread":
        return ThreadPoolTaskRunner(max_workers=workers)
    if runner == "dask":
        from prefect_dask import DaskTaskRunner

        if dask_address:
            return DaskTaskRunner(address=dask_address)
        return DaskTaskRunner(cluster_kwargs={"n_workers": workers, "threads_per_worker": 1,
                                              "processes": True, "dashboard_address": None})
    raise ValueError(f"unknown runner '{runner}': use thread or dask")


def run(inbox: str, db: str, *, gap_fill: str | None = None, lift: str | None = None,
        export_usd: bool = True, compare: tuple[str, ...] = (),
        workers: int = DEFAULT_WORKERS, runner: str = "thread",
        dask_address: str | None = None) -> BuildSummary:
    """Run :func:`build` on the chosen task runner.

    Dask runs tasks in worker processes, which report to this process's Prefect API
    (:func:`~handdb_flows.settings.shared_api`).
    """
    flow_ = build.with_options(task_runner=task_runner(runner, workers, dask_address))
    api = shared_api() if runner == "dask" else contextlib.nullcontext()
    with api:
        return flow_(inbox=inbox, db=db, gap_fill=gap_fill, lift=lift, export_usd=export_usd,
                     compare=list(compare),
                     window=workers * WINDOW_PER_WORKER)


@flow(name="handdb-build", log_prints=False,
      task_runner=cast(TaskRunner[PrefectFuture[Any]],
                       ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS)))
def build(
    inbox: str,
    db: str,
    gap_fill: str | None = None,
    lift: str | None = None,
    export_usd: bool = True,
    compare: list[str] | None = None,
    window: int = DEFAULT_WORKERS * WINDOW_PER_WORKER,
) -> BuildSummary:
    """Build the database at ``db`` from the inbox folder ``inbox``.

    New and changed clips are processed; unchanged clips cost a hash each. Returns a
    :class:`BuildSummary`; a ``runs`` row records it.
    """
    logger = get_run_logger()
    started = datetime.now(UTC)
    options = pipeline.BuildOptions(gap_fill=gap_fill, lift=lift, export_usd=export_usd,
                                    compare=tuple(compare or ()))
    summary = BuildSummary(run_id=uuid.uuid4().hex[:12], inbox=inbox, db=db)
    store = Store(db)
    with store.lock(), threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        removed = store.remove_temporaries()
        if removed:
            logger.warning("removed %d half-written files left by an interrupted build", removed)
        t0 = time.perf_counter()
        scan = scan_inbox(inbox)
        summary.n_clips = len(scan.clips)
        progress.expect(summary.n_clips)
        summary.refusals.extend(Refusal.from_error(e) for e in scan.refused)
        ratios, xray_refusals = xray_ratios(list(scan.others.get("xray", ())), db)
        summary.refusals.extend(xray_refusals)
        ratios_hash = pipeline.table_hash(ratios)
        committed = store.clip_build_keys()
        todo = []
        for entry in scan.clips:
            key = pipeline.build_key(content_hash(entry), options, ratios_hash)
            if committed.get(entry.clip_id) == key:
                summary.unchanged.append(entry.clip_id)
                progress.advance(entry.clip_id, "unchanged")
            else:
                todo.append((entry, key))
        summary.timings["scan"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        window = max(1, window)
        for start in range(0, len(todo), window):
            chains = {entry.clip_id: _run_clip_chain(entry, key, db, inbox, ratios, options)
                      for entry, key in todo[start:start + window]}
            for clip_id, chain in chains.items():
                wait(list(chain.values()))
                failure = _chain_failure(chain)
                if failure:
                    summary.failed[clip_id] = failure
                    progress.advance(clip_id, "failed")
                    logger.error("clip %s failed: %s", clip_id, failure)
                    continue
                outcome = chain["commit"].result()
                if isinstance(outcome, Refusal):
                    summary.refusals.append(outcome)
                    progress.advance(clip_id, "refused")
                    logger.warning("clip %s refused: %s", clip_id, outcome)
                else:
                    summary.processed.append(clip_id)
                    summary.n_frames += outcome.clip.n_frames
                    if outcome.validation is not None:
                        summary.validation[clip_id] = clip_summary(outcome.validation)
        summary.timings["clips"] = time.perf_counter() - t0

        previous = store.read_table("quarantine")
        refused = quarantine_table(summary.refusals, inbox, previous)
        if not refused.equals(previous):
            store.write("quarantine", "quarantine", refused)
        _record_run(store, summary, options, started)
    create_markdown_artifact(markdown=summary_markdown(summary), key="handdb-build",
                             description="handdb build summary")
    return summary


def summary_markdown(summary: BuildSummary) -> str:
    """Write a markdown report of a build."""
    lines = [
        f"# handdb build {summary.run_id}",
        "",
        f"- inbox: `{summary.inbox}`, database: `{summary.db}`",
        f"- clips in the inbox: {summary.n_clips}; processed {len(summary.processed)}, "
        f"unchanged {len(summary.unchanged)}, failed {len(summary.failed)}",
        f"- frames processed: {summary.n_frames}",
        f"- refused inputs (quarantine): {len(summary.refusals)}",
    ]
    if summary.refusals:
        lines += ["", "| file | line | field | reason |", "|---|---|---|---|"]
        lines += [f"| {r.file} | {r.line or ''} | {r.field or ''} | {r.reason} |"
                  for r in summary.refusals]
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


def _record_run(store: Store, summary: BuildSummary, options: pipeline.BuildOptions,
                started: datetime) -> None:
    params = {"inbox": summary.inbox, "db": summary.db, **asdict(options)}
    row = tables.from_columns("runs", {
        "run_id": [summary.run_id],
        "flow": ["handdb-build"],
        "started_at": [started],
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
    })
    store.write("runs", f"{started:%Y%m%dT%H%M%S}-{summary.run_id}", row)

