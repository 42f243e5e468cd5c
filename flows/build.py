"""The build flow: the library's build with one Prefect task per clip.

:class:`handdb.build.Build` plans the build, stores the X-ray tables and, at the end, writes
the quarantine table and the run record; each clip to process is one task,
``process <clip_id>``, that runs :func:`handdb.build.process_clip` (every stage and the
commit). At most ``window`` tasks are in flight, a new one submitted as each finishes
(:func:`handdb.build.window.sliding_window`), so memory is bounded by the largest clips in
flight and a slow clip holds back no other. A task is retried only on I/O errors; refused
input comes back as a value and ends in the ``quarantine`` table. The flow publishes the
build summary and each validated clip's depth errors as markdown artifacts.

What the run's page in the Prefect UI shows is worded by :mod:`handdb.build.describe`: an
INFO log line per clip (sent to the API; the terminal shows warnings only, see
:mod:`handdb_flows`), the run's name (from the plan when it starts, from what it did when it
ends), and its final state: ``Completed``, ``Completed with refusals`` when an input was
refused, ``Failed`` when a stage failed on a clip, each with a message that counts them.
The flow run's id, and its page when a lasting server shows it, go into the ``runs`` row.
The summary artifact is keyed per database and published under its key only when the
build changed something, so that a scheduled build with nothing to do leaves the latest
summary standing (it still attaches its own, unkeyed, to its run).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Collection
from contextlib import nullcontext
from logging import ERROR, INFO
from pathlib import Path
from typing import Any, cast

from handdb_flows.serve import absolute_location
from handdb_flows.settings import lasting_run_url
from prefect import flow, get_run_logger, task
from prefect.artifacts import create_markdown_artifact
from prefect.cache_policies import NO_CACHE
from prefect.client.orchestration import get_client
from prefect.futures import PrefectFuture, as_completed
from prefect.runtime import flow_run
from prefect.states import Completed, Failed, State
from prefect.task_runners import TaskRunner, ThreadPoolTaskRunner
from threadpoolctl import threadpool_limits

from handdb.build import (
    BLAS_THREADS,
    DEFAULT_WORKERS,
    FLOW_NAME,
    Build,
    BuildContext,
    BuildOptions,
    PlannedClip,
    StageFailed,
    process_clip,
    summary_markdown,
)
from handdb.build.describe import (
    OutcomeKind,
    clip_line,
    planned_run_name,
    run_name,
    run_outcome,
)
from handdb.build.stages import ClipResult
from handdb.build.window import IN_FLIGHT_PER_WORKER, sliding_window
from handdb.store import Store
from handdb.store.quarantine import Refusal

#: Clips in flight per worker; bounds memory and the thread pool's queue.
WINDOW_PER_WORKER = IN_FLIGHT_PER_WORKER

#: Hex digits of the database location's hash in its summary artifact's key.
DB_KEY_DIGITS = 8

#: The flow's description, shown on its page and its deployment's (markdown, not the
#: docstring's reStructuredText).
DESCRIPTION = """\
Build the handdb database from an inbox folder of hand keypoint clips.

New and changed clips are processed, one task per clip, each from its first changed
stage (ingest, bone lengths, gap filling, lifting, validation, export); unchanged clips
cost a hash each. Refused inputs go to the `quarantine` table, and every build writes a
`runs` row.

- **State**: *Completed*, *Completed with refusals* (some input was refused; the rest is
  built), or *Failed* (a stage failed on a clip); its message counts the clips.
- **Logs**: one line per clip: the stages it ran, or why it was refused or failed.
- **Artifacts**: the build summary (`handdb-build-...`, one key per database) and each
  validated clip's depth errors (`validation-<clip>`).
"""


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


def first_done(futures: Collection[PrefectFuture]) -> PrefectFuture:
    """The first of ``futures`` to finish, with its final state.

    ``wait`` keeps the state the task ended in; without it, ``state`` asks the server,
    which may not have recorded the end yet.
    """
    future = next(as_completed(list(futures)))
    future.wait()
    return future


def summary_key(db: str) -> str:
    """The key of the build summary artifact of the database ``db``.

    One key per database, so that Prefect's versions of it are that database's history:
    its folder's name, for reading, and a hash of its absolute location, for telling apart
    databases of one name.
    """
    location = absolute_location(db)
    digest = hashlib.sha256(location.encode()).hexdigest()[:DB_KEY_DIGITS]
    return artifact_key(FLOW_NAME, f"{Path(location).name}-{digest}")


def _rename(name: str) -> None:
    """Rename the current flow run."""
    with get_client(sync_client=True) as client:
        client.update_flow_run(flow_run.id, name=name)


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


@flow(name=FLOW_NAME, description=DESCRIPTION, log_prints=False, validate_parameters=False,
      task_runner=cast(TaskRunner[PrefectFuture[Any]],
                       ThreadPoolTaskRunner(max_workers=DEFAULT_WORKERS)))
def build(inbox: str, db: str, gap_fill: str | None = None, lift: str | None = None,
          export_usd: bool = True, compare: list[str] | None = None,
          window: int = DEFAULT_WORKERS * WINDOW_PER_WORKER, locked: bool = False
          ) -> State:
    """Build the database at ``db`` from the inbox folder ``inbox``.

    New and changed clips are processed, each from its first changed stage; unchanged
    clips cost a hash each. Returns the final state, holding the
    :class:`~handdb.build.BuildSummary` (``Failed`` when a stage failed on a clip); a
    ``runs`` row records it. ``locked``: the caller holds the database lock (the
    orchestrator takes it before the flow starts, so that a second build is refused without
    a failed flow run); else the flow takes it.
    """
    logger = get_run_logger()
    options = BuildOptions(gap_fill=gap_fill, lift=lift, export_usd=export_usd,
                           compare=tuple(compare or ())).check()
    with (nullcontext() if locked else Store(db).lock(),
          threadpool_limits(limits=BLAS_THREADS, user_api="blas")):
        run = Build.begin(inbox, db, options, flow_run_id=str(flow_run.id),
                          flow_run_url=lasting_run_url())
        _rename(planned_run_name(run.plan))
        if run.summary.removed_temporaries:
            logger.warning("removed %d half-written files left by an interrupted build",
                           run.summary.removed_temporaries)
        for repair in run.summary.repairs:
            logger.warning("repaired %s", repair)
        context, todo = run.context, run.todo
        finished = sliding_window(todo, window, lambda item: process.submit(item, context),
                                  first_done)
        for item, future in finished:
            outcome = _outcome(future)
            # a refusal is the input's, reported by the summary and the quarantine (a
            # warning would print it twice); a failure is the database storage's, worth the
            # terminal's attention
            failed = isinstance(outcome, StageFailed)
            logger.log(ERROR if failed else INFO, "%s", clip_line(item, outcome))
            run.record(item.clip_id, outcome)
        summary = run.finish()
    # only a build that changed something becomes the latest version of the keyed summary
    key = summary_key(db) if summary.changed or summary.failed else None
    create_markdown_artifact(markdown=summary_markdown(summary), key=key,
                             description=f"handdb build summary of {db}")
    _rename(run_name(summary))
    ending = run_outcome(summary)
    final = Failed if ending.kind is OutcomeKind.failed else Completed
    return final(name=ending.name, message=ending.message, data=summary)
