"""The gap-filling evaluation flow: score every method on clips with complete tracks.

One task per clip loads it from its source (:mod:`handdb.gapfill.sources`), hides known
points under each mask, fills them with every method
(:func:`handdb.gapfill.evaluate.evaluate_clip`) and writes the ``gapfill_eval`` rows and
the chart into the database. The flow publishes the pooled RMSE per method and mask as a
markdown artifact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import pyarrow as pa
from prefect import flow, task
from prefect.artifacts import create_markdown_artifact
from prefect.cache_policies import NO_CACHE
from prefect.futures import PrefectFuture
from prefect.task_runners import TaskRunner, ThreadPoolTaskRunner
from threadpoolctl import threadpool_limits

from handdb_flows.build import BLAS_THREADS, DEFAULT_WORKERS
from handdb.gapfill.evaluate import OCCLUSION_MASK, evaluate_clip, rmse_markdown
from handdb.gapfill.sources import ClipSource, store_evaluation
from handdb.store import tables
from handdb.store.database import Store


@dataclass
class EvalSummary:
    """What an evaluation run did: the rows of every clip scored, and the clips skipped."""

    table: pa.Table
    charts: dict[str, str] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)


@task(name="gapfill-eval-clip", task_run_name="gapfill eval {source.clip_id}",
      cache_policy=NO_CACHE)
def evaluate_source(
    source: ClipSource, db: str, masks: Sequence[str], methods: Sequence[str], seed: int
) -> tuple[pa.Table, str] | None:
    """Score one clip and write its rows and chart; ``None`` if it cannot be scored."""
    clip = source.load()
    if clip is None:
        return None
    usable = [m for m in masks if m != OCCLUSION_MASK or clip.xyz is not None]
    evaluation = evaluate_clip(clip.clip_id, clip.uv, clip.skeleton, masks=usable,
                               methods=methods, xyz=clip.xyz, seed=seed)
    chart = store_evaluation(Store(db), clip, evaluation, methods)
    return evaluation.table, chart


@flow(name="handdb-gapfill-eval", log_prints=False, validate_parameters=False,
      task_runner=cast(TaskRunner[PrefectFuture[Any]],
                       ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS)))
def gapfill_eval(
    sources: list[ClipSource], db: str, masks: list[str], methods: list[str], seed: int = 0
) -> EvalSummary:
    """Evaluate every gap-filling method on each source's clip into the database ``db``."""
    with threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        futures = [evaluate_source.submit(s, db, masks, methods, seed) for s in sources]
        results = [future.result() for future in futures]
    done = [result for result in results if result is not None]
    summary = EvalSummary(
        table=pa.concat_tables([t for t, _ in done]) if done else tables.empty("gapfill_eval"),
        charts={s.clip_id: r[1] for s, r in zip(sources, results, strict=True) if r},
        skipped=[s.clip_id for s, r in zip(sources, results, strict=True) if r is None],
    )
    create_markdown_artifact(markdown=summary_markdown(summary), key="handdb-gapfill-eval",
                             description="gap-filling RMSE per method and mask")
    return summary


def summary_markdown(summary: EvalSummary) -> str:
    """Write a markdown report: the pooled RMSE table and the clips scored or skipped."""
    lines = ["# Gap filling: RMSE over hidden points, pixels", ""]
    if summary.table.num_rows:
        lines += [rmse_markdown(summary.table), ""]
    lines.append(f"Clips scored: {', '.join(summary.charts) or 'none'}.")
    if summary.skipped:
        lines.append(f"Skipped (incomplete tracks or refused files): "
                     f"{', '.join(summary.skipped)}.")
    return "\n".join(lines)
