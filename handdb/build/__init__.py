"""The build: inbox → database, with or without an orchestrator.

:func:`run_build` is the one entry point (the command line's ``handdb build``): it checks the
options, plans with the library alone (:mod:`handdb.build.plan`), finishes at once when
there is nothing to do, and otherwise runs the clips on the chosen runner: ``local`` (this
process, :func:`build_in_process`) or an orchestrator's (:mod:`handdb.build.orchestrators`;
Prefect's ``thread`` and ``dask``). Whatever runs them, each clip goes through
:func:`~handdb.build.process.process_clip` and the build through :class:`Build`.

Each name below is imported from its module on first use, so that the command line can
ask which runners exist (:mod:`handdb.build.orchestrators`) without loading the stages.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from handdb.lazy import lazy_attributes

if TYPE_CHECKING:
    from handdb.build.context import BuildContext, StageFailed
    from handdb.build.entry import run_build
    from handdb.build.options import BuildOptions
    from handdb.build.orchestrators import (
        DEFAULT_RUNNER,
        LOCAL_RUNNER,
        load_orchestrator,
        runner_names,
    )
    from handdb.build.plan import BuildPlan, PlannedClip, plan_build
    from handdb.build.process import process_clip
    from handdb.build.run import (
        BLAS_THREADS,
        DEFAULT_WORKERS,
        FLOW_NAME,
        Build,
        BuildSummary,
        build_in_process,
        run_clip,
        summary_markdown,
    )

#: Exported name -> the module that defines it.
_EXPORTS = {
    "BuildOptions": "handdb.build.options",
    "DEFAULT_RUNNER": "handdb.build.orchestrators",
    "LOCAL_RUNNER": "handdb.build.orchestrators",
    "load_orchestrator": "handdb.build.orchestrators",
    "runner_names": "handdb.build.orchestrators",
    "BuildPlan": "handdb.build.plan",
    "PlannedClip": "handdb.build.plan",
    "plan_build": "handdb.build.plan",
    "BuildContext": "handdb.build.context",
    "StageFailed": "handdb.build.context",
    "process_clip": "handdb.build.process",
    "BLAS_THREADS": "handdb.build.run",
    "DEFAULT_WORKERS": "handdb.build.run",
    "FLOW_NAME": "handdb.build.run",
    "Build": "handdb.build.run",
    "BuildSummary": "handdb.build.run",
    "build_in_process": "handdb.build.run",
    "run_clip": "handdb.build.run",
    "summary_markdown": "handdb.build.run",
    "run_build": "handdb.build.entry",
}

__getattr__ = lazy_attributes(__name__, _EXPORTS)

__all__ = [
    "BLAS_THREADS",
    "DEFAULT_RUNNER",
    "DEFAULT_WORKERS",
    "FLOW_NAME",
    "LOCAL_RUNNER",
    "Build",
    "BuildContext",
    "BuildOptions",
    "BuildPlan",
    "BuildSummary",
    "PlannedClip",
    "StageFailed",
    "build_in_process",
    "load_orchestrator",
    "plan_build",
    "process_clip",
    "run_build",
    "run_clip",
    "runner_names",
    "summary_markdown",
]
