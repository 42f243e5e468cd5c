"""Who runs a build: this process, or an orchestrator installed beside handdb.

The library builds on its own (:func:`~handdb.build.run.build_in_process`, the ``local``
runner). An orchestrator adds task runs, retries, artifacts and schedules; it plugs in
through entry points, so the library never imports it: the group :data:`ORCHESTRATORS`
names orchestrators, the group :data:`RUNNERS` names the task runners they offer (both
point at the orchestrator object; names are listed without importing it). handdb's own is
the Prefect one in the repository's ``flows/`` folder (installed as ``handdb_flows``), with
the runners ``thread`` and ``dask``.
"""

from __future__ import annotations

from collections.abc import Sequence
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, Any, Protocol

from handdb.errors import HanddbError, UnknownNameError

if TYPE_CHECKING:
    from handdb.build.options import BuildOptions
    from handdb.build.run import BuildSummary

#: Entry point group of orchestrators (``name = "module:object"``).
ORCHESTRATORS = "handdb.orchestrators"

#: Entry point group of task runners: ``runner name = "module:orchestrator object"``.
RUNNERS = "handdb.runners"

#: The orchestrator the command line uses.
DEFAULT_ORCHESTRATOR = "prefect"

#: The runner that builds in this process, without an orchestrator.
LOCAL_RUNNER = "local"

#: The runner the command line uses.
DEFAULT_RUNNER = "thread"


class Orchestrator(Protocol):
    """What an orchestrator offers: builds on its runners, scheduled builds, evaluations."""

    def build(self, inbox: str, db: str, options: BuildOptions, *, runner: str,
              workers: int, address: str | None = None, locked: bool = False
              ) -> BuildSummary:
        """Build ``db`` from ``inbox`` with the task runner ``runner``.

        ``locked``: the caller holds the database lock (``Store(db).lock()``) until this
        returns, and the build must not take it again; else the build takes it.
        """

    def serve(self, inbox: str, db: str, *, cron: str | None, interval: float | None
              ) -> None:
        """Build on a schedule until stopped."""

    def gapfill_eval(self, sources: Sequence[Any], db: str, masks: list[str],
                     methods: list[str], seed: int) -> Any:
        """Score gap-filling methods on each source's clip (one task per clip)."""


class OrchestratorMissing(HanddbError):
    """An orchestrator that is not installed."""


def _load(group: str, name: str, what: str) -> Orchestrator:
    found = entry_points(group=group, name=name)
    if not found:
        raise OrchestratorMissing(
            f"no {what} '{name}' is installed (entry point group {group}); install handdb "
            f"with its flows, or build with --runner {LOCAL_RUNNER}")
    orchestrator: Orchestrator = next(iter(found)).load()
    return orchestrator


def load_orchestrator(name: str = DEFAULT_ORCHESTRATOR) -> Orchestrator:
    """The orchestrator registered under ``name``.

    Raises
    ------
    OrchestratorMissing
        When no installed package registers it.
    """
    return _load(ORCHESTRATORS, name, "orchestrator")


def runner_orchestrator(runner: str) -> Orchestrator:
    """The orchestrator that offers the task runner ``runner``."""
    return _load(RUNNERS, runner, "runner")


def runner_names() -> tuple[str, ...]:
    """Every runner a build can use: the orchestrators' (the default first), then ``local``."""
    names = sorted(ep.name for ep in entry_points(group=RUNNERS))
    return (*sorted(names, key=lambda n: n != DEFAULT_RUNNER), LOCAL_RUNNER)


def check_runner(runner: str) -> str:
    """Return ``runner`` if a build can use it, else raise :class:`UnknownNameError`."""
    names = runner_names()
    if runner not in names:
        raise UnknownNameError("runner", runner, names)
    return runner
