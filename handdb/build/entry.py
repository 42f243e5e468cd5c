"""The one entry point of a build, :func:`run_build`: check, plan, and hand the clips over.

It checks the options, plans with the library alone (:mod:`handdb.build.plan`), finishes at
once when there is nothing to do, and otherwise runs the clips on the chosen runner:
``local`` (this process, :func:`~handdb.build.run.build_in_process`) or an orchestrator's
(:mod:`handdb.build.orchestrators`; Prefect's ``thread`` and ``dask``).
"""

from __future__ import annotations

import time
from pathlib import Path

from handdb.build.options import BuildOptions
from handdb.build.orchestrators import (
    DEFAULT_RUNNER,
    LOCAL_RUNNER,
    check_runner,
    runner_orchestrator,
)
from handdb.build.plan import plan_build
from handdb.build.run import DEFAULT_WORKERS, BuildSummary, build_in_process
from handdb.errors import InputError
from handdb.store.database import Store

#: The key of :attr:`BuildSummary.timings` holding the wall time of the whole
#: :func:`run_build`, seconds: planning, starting and stopping the orchestrator (its
#: temporary server takes most of it) and the clips. The ``runs`` row's timings, written
#: before it ends, hold the build's own work only: ``scan`` (planning inside the build) and
#: ``clips`` (every clip, start to last commit).
TOTAL = "total"


def run_build(inbox: str | Path, db: str, options: BuildOptions | None = None, *,
              runner: str = DEFAULT_RUNNER, workers: int = DEFAULT_WORKERS,
              address: str | None = None) -> BuildSummary:
    """Build the database ``db`` from the inbox folder ``inbox``.

    Parameters
    ----------
    inbox, db
        The inbox folder; the database folder or fsspec URL.
    options
        What to compute (default: every sidecar's choice, else the default methods).
    runner
        ``local`` (this process), or a runner of an installed orchestrator
        (:func:`~handdb.build.orchestrators.runner_names`).
    workers
        Clips processed at once.
    address
        The runner's cluster, for runners that take one (Dask's scheduler address).

    Returns
    -------
    BuildSummary
        What the build did; its ``timings[TOTAL]`` is this call's wall time.

    Raises
    ------
    UnknownNameError
        For an unknown runner or method, before anything runs.
    InputError
        If ``inbox`` is not a folder.
    DatabaseLockedError
        If another build holds the database.
    """
    clock = time.perf_counter()
    options = (options or BuildOptions()).check()
    check_runner(runner)
    if not Path(inbox).is_dir():
        raise InputError(inbox, "is not a folder: create it and put clips in it, or pass "
                         "--inbox (or set HANDDB_INBOX)", field="inbox")
    summary = _dispatch(inbox, db, options, runner=runner, workers=workers, address=address)
    summary.timings[TOTAL] = time.perf_counter() - clock
    return summary


def _dispatch(inbox: str | Path, db: str, options: BuildOptions, *, runner: str,
              workers: int, address: str | None) -> BuildSummary:
    """Plan under the database lock and run the clips where :func:`run_build` says."""
    with Store(db).lock():
        plan = plan_build(inbox, db, options)
        if plan.todo and runner != LOCAL_RUNNER:
            # The lock is held from before the plan to the end of the orchestrator's run:
            # a second build is refused here, with the library's message, before the
            # orchestrator starts (inside a Prefect flow the refusal is an ERROR log).
            return runner_orchestrator(runner).build(str(inbox), db, options,
                                                     runner=runner, workers=workers,
                                                     address=address, locked=True)
    # Without a clip to process, what is left (the X-ray tables, the quarantine, the run
    # record) takes milliseconds here and seconds to start an orchestrator for.
    return build_in_process(inbox, db, options, workers=workers, plan=plan)
