"""handdb's Prefect orchestrator: builds, scheduled builds and evaluations as flows.

It is registered under the entry points ``handdb.orchestrators`` (``prefect``) and
``handdb.runners`` (``thread``, ``dask``); the library finds it there
(:mod:`handdb.build.orchestrators`) and calls it with plain arguments. Prefect is imported
only when it runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import nullcontext
from typing import Any

from handdb.build import BuildOptions, BuildSummary
from handdb.store import Store

#: Task runners this orchestrator offers.
RUNNERS: tuple[str, ...] = ("thread", "dask")


def task_runner(runner: str, workers: int, address: str | None = None) -> Any:
    """The Prefect task runner for per-clip tasks: a bounded thread pool, or Dask.

    ``dask`` starts a local Dask cluster of ``workers`` processes unless ``address``
    names an existing scheduler.
    """
    if runner == "thread":
        from prefect.task_runners import ThreadPoolTaskRunner

        return ThreadPoolTaskRunner(max_workers=workers)
    if runner == "dask":
        from prefect_dask import DaskTaskRunner

        if address:
            return DaskTaskRunner(address=address)
        return DaskTaskRunner(cluster_kwargs={"n_workers": workers, "threads_per_worker": 1,
                                              "processes": True, "dashboard_address": None})
    raise ValueError(f"unknown runner '{runner}': use one of {', '.join(RUNNERS)}")


class PrefectOrchestrator:
    """Builds, scheduled builds and evaluations as Prefect flows."""

    runners = RUNNERS

    def build(self, inbox: str, db: str, options: BuildOptions, *, runner: str = "thread",
              workers: int = 4, address: str | None = None, locked: bool = False
              ) -> BuildSummary:
        """Run the build flow on ``runner``.

        Unless the caller holds the database lock (``locked``, as
        :func:`handdb.build.run_build` does), it is taken here, before the flow starts: a
        second build is refused with the library's message, not inside a flow run.

        The Prefect API is this process's (:func:`~handdb_flows.settings.shared_api`):
        Dask's worker processes report to it, and a temporary server started for it ends
        with this process, even when the build is killed. A build that failed on a clip
        ends in a ``Failed`` state and still returns its summary; one that could not run
        at all raises what stopped it.
        """
        from handdb_flows.build import WINDOW_PER_WORKER, build
        from handdb_flows.settings import quick_flows, shared_api

        flow_ = build.with_options(task_runner=task_runner(runner, workers, address))
        with nullcontext() if locked else Store(db).lock(), quick_flows(), shared_api():
            state = flow_(inbox=inbox, db=db, gap_fill=options.gap_fill, lift=options.lift,
                          export_usd=options.export_usd, compare=list(options.compare),
                          window=workers * WINDOW_PER_WORKER, locked=True, return_state=True)
            outcome = state.result(raise_on_failure=False)
        if isinstance(outcome, BaseException):
            raise outcome
        if not isinstance(outcome, BuildSummary):
            raise RuntimeError(f"the build flow ended in state {state.name!r} "
                               f"({state.message}) without a build summary")
        return outcome

    def serve(self, inbox: str, db: str, *, cron: str | None, interval: float | None
              ) -> None:
        """Serve the build flow as a scheduled Prefect deployment until stopped."""
        from handdb_flows.serve import serve_build

        serve_build(inbox=inbox, db=db, cron=cron, interval=interval)

    def gapfill_eval(self, sources: Sequence[Any], db: str, masks: list[str],
                     methods: list[str], seed: int) -> Any:
        """Run the gap-filling evaluation flow, one task per clip."""
        from handdb_flows.gapfill_eval import gapfill_eval
        from handdb_flows.settings import quick_flows

        with quick_flows():
            return gapfill_eval(list(sources), db, masks, methods, seed)


#: The object the entry points name.
PREFECT = PrefectOrchestrator()
