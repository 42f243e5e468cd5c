"""The gap-filling evaluation flow: score every method on clips with complete tracks.

One task per clip runs :func:`handdb.gapfill.sources.evaluate_source` (load the clip from its
source, hide known points under each mask, fill them with every method, store the
``gapfill_eval`` rows and the chart). The flow publishes the pooled RMSE per method and mask
as a markdown artifact.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import pyarrow as pa
from prefect import flow, task
from prefect.artifacts import create_markdown_artifact
from prefect.cache_policies import NO_CACHE
from prefect.futures import PrefectFuture
from prefect.task_runners import TaskRunner, ThreadPoolTaskRunner
from threadpoolctl import threadpool_limits

from handdb.build import BLAS_THREADS, DEFAULT_WORKERS
from handdb.gapfill.sources import (
    ClipSource,
    EvalSummary,
    evaluate_source,
    summarise,
    summary_markdown,
)


@task(name="gapfill-eval-clip", task_run_name="gapfill eval {source.clip_id}",
      cache_policy=NO_CACHE)
def evaluate(source: ClipSource, db: str, masks: Sequence[str], methods: Sequence[str],
             seed: int) -> tuple[pa.Table, str] | None:
    """Score one clip and store its rows and chart; ``None`` if it cannot be scored."""
    return evaluate_source(source, db, masks, methods, seed)


@flow(name="handdb-gapfill-eval", log_prints=False, validate_parameters=False,
      task_runner=cast(TaskRunner[PrefectFuture[Any]],
                       ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS)))
def gapfill_eval(
    sources: list[ClipSource], db: str, masks: list[str], methods: list[str], seed: int = 0
) -> EvalSummary:
    """Evaluate every gap-filling method on each source's clip into the database ``db``."""
    with threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        futures = [evaluate.submit(s, db, masks, methods, seed) for s in sources]
        summary = summarise(sources, [future.result() for future in futures])
    create_markdown_artifact(markdown=summary_markdown(summary), key="handdb-gapfill-eval",
                             description="gap-filling RMSE per method and mask")
    return summary
