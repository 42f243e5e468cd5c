"""The build flow: the library's build with one Prefect task per clip.

:class:`handdb.build.Build` plans the build, stores the X-ray tables and, at the end, writes
the quarantine table and the run record; each clip to process is one task,
``process <clip_id>``, that runs :func:`handdb.build.process_clip` (every stage and the
commit). At most ``window`` tasks are in flight, a new one submitted as each finishes
(:func:`handdb.build.window.sliding_window`), so memory is bounded by the largest clips in
flight and a slow clip holds back no other. A task is retried only on I/O errors; refused
input comes back as a value and ends in the ``quarantine`` table. The flow publishes the
build summary and each validated clip's depth errors as markdown artifacts.
"""

from __future__ import annotations

import re
from collections.abc import Collection
from contextlib import nullcontext
from typing import Any, cast

from prefect import flow, get_run_logger, task
from prefect.artifacts import create_markdown_artifact
from prefect.cache_policies import NO_CACHE
from prefect.futures import PrefectFuture, as_completed
from prefect.task_runners import TaskRunner, ThreadPoolTaskRunner
from threadpoolctl import threadpool_limits

from handdb.build import (
    BLAS_THREADS,
    DEFAULT_WORKERS,
    FLOW_NAME,
    Build,
    BuildContext,
    BuildOptions,
    BuildSummary,
    PlannedClip,
    StageFailed,
    process_clip,
    summary_markdown,
)
from handdb.build.stages import ClipResult
from handdb.build.window import IN_FLIGHT_PER_WORKER, sliding_window
from handdb.store import Store
from handdb.store.quarantine import Refusal

#: Clips in flight per worker; bounds memory and the thread pool's queue.
WINDOW_PER_WORKER = IN_FLIGHT_PER_WORKER


def _retry_on_io(task: Any, task_run: Any, state: Any) -> bool:
    """Retry a task only for I/O errors, never for refused input or a bug."""
    try:
        state.result()
    except StageFailed as failure:
        return isinstance(failure.__cause__, OSError)
    except OSError:
        return True
    except Exception:  # noqa: BLE001 - any other failure is final
        return False
    return False


IO_RETRIES: dict[str, Any] = {"retries": 2, "retry_delay_seconds": 1,
                             "retry_condition_fn": _retry_on_io}


def artifact_key(kind: str, clip_id: str) -> str:
    """Return a Prefect artifact key (lowercase letters, digits, dashes) for a clip."""
    return re.sub(r"[^a-z0-9-]+", "-", f"{kind}-{clip_id}".lower()).strip("-")


@task(name="process", task_run_name="process {item.clip_id}", cache_policy=NO_CACHE,
      **IO_RETRIES)
def process(item: PlannedClip, context: BuildContext) -> ClipResult | Refusal:
    """Run one clip's stages and commit it; publish its validation."""
    outcome = process_clip(item, context)
    if isinstance(outcome, ClipResult) and outcome.report is not None:
        create_markdown_artifact(markdown=outcome.report,
                                 key=artifact_key("validation", item.clip_id),
                                 description=f"depth validation of clip {item.clip_id}")
    return outcome


def _first_done(futures: Collection[PrefectFuture]) -> PrefectFuture:
    """The first of ``futures`` to finish, with its final state.

    ``wait`` keeps the state the task ended in; without it, ``state`` asks the server,
    which may not have recorded the end yet.
    """
    future = next(as_completed(list(futures)))
    future.wait()
    return future


def _outcome(future: PrefectFuture) -> ClipResult | Refusal | StageFailed:
    """The task's value, or the stage failure that ended it."""
    state = future.state
    if state.is_completed():
        return future.result()
    try:
        future.result()
    except StageFailed as failure:
        return failure
    except Exception as error:  # noqa: BLE001 - a task that failed outside any stage
        return StageFailed(str(future.task_run_id), "task", error)
    return StageFailed(str(future.task_run_id), "task", RuntimeError(state.message or ""))


@flow(name=FLOW_NAME, log_prints=False, validate_parameters=False,
      task_runner=cast(TaskRunner[PrefectFuture[Any]],
                       ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS)))
def build(inbox: str, db: str, gap_fill: str | None = None, lift: str | None = None,
          export_usd: bool = True, compare: list[str] | None = None,
          window: int = DEFAULT_WORKERS * WINDOW_PER_WORKER, locked: bool = False
          ) -> BuildSummary:
    """Build the database at ``db`` from the inbox folder ``inbox``.

    New and changed clips are processed, each from its first changed stage; unchanged
    clips cost a hash each. Returns the :class:`~handdb.build.BuildSummary`; a ``runs`` row
    records it. ``locked``: the caller holds the database lock (the orchestrator takes it
    before the flow starts, so that a second build is refused without a failed flow run);
    else the flow takes it.
    """
    logger = get_run_logger()
    options = BuildOptions(gap_fill=gap_fill, lift=lift, export_usd=export_usd,
                           compare=tuple(compare or ())).check()
    with (nullcontext() if locked else Store(db).lock(),
          threadpool_limits(limits=BLAS_THREADS, user_api="blas")):
        run = Build.begin(inbox, db, options)
        if run.summary.removed_temporaries:
            logger.warning("removed %d half-written files left by an interrupted build",
                           run.summary.removed_temporaries)
        for repair in run.summary.repairs:
            logger.warning("repaired %s", repair)
        context, todo = run.context, run.todo
        finished = sliding_window(todo, window, lambda item: process.submit(item, context),
                                  _first_done)
        for item, future in finished:
            outcome = _outcome(future)
            if isinstance(outcome, StageFailed):
                logger.error("clip %s failed: %s", item.clip_id, outcome)
            elif isinstance(outcome, Refusal):
                # the summary and the quarantine report it; a warning would print it twice
                logger.info("clip %s refused: %s", item.clip_id, outcome)
            run.record(item.clip_id, outcome)
        summary = run.finish()
    create_markdown_artifact(markdown=summary_markdown(summary), key="handdb-build",
                             description="handdb build summary")
    return summary
