"""Prefect settings handdb runs its flows with."""

from __future__ import annotations

import contextlib
import subprocess
from collections.abc import Iterator
from functools import cache

from handdb_flows.reaper import stop_with_this_process
from prefect.settings import (
    PREFECT_API_URL,
    PREFECT_FLOWS_HEARTBEAT_FREQUENCY,
    temporary_settings,
)


@contextlib.contextmanager
def quick_flows() -> Iterator[None]:
    """Run flows without the heartbeat thread, whose join costs about 1 s per flow run."""
    with temporary_settings({PREFECT_FLOWS_HEARTBEAT_FREQUENCY: None}):
        yield


@contextlib.contextmanager
def shared_api() -> Iterator[str]:
    """Make tasks in other processes report to this process's Prefect API; yield its URL.

    With no ``PREFECT_API_URL`` set, Prefect gives each process its own temporary server.
    A Dask worker process would then start one of its own (13-17 s), and two tasks
    starting it at once on one worker race and fail ("Server process did not start").
    Here the temporary server is started once, in this process, and its loopback URL goes
    into the settings that task runners send with every task. Workers on other machines
    cannot reach a loopback URL: for those, set ``PREFECT_API_URL`` to a real server.

    The temporary server ends with this process, even when this process is killed
    (:func:`~handdb_flows.reaper.stop_with_this_process`); Prefect stops it at a normal
    exit.
    """
    configured = PREFECT_API_URL.value()
    if configured:
        yield configured
        return
    from prefect.server.api.server import SubprocessASGIServer

    server = SubprocessASGIServer()
    server.start()
    _reaped(server.server_process.pid)
    with temporary_settings({PREFECT_API_URL: server.api_url}):
        yield server.api_url


@cache
def _reaped(pid: int) -> subprocess.Popen:
    """The reaper of process ``pid``, started once however often the server is reused."""
    return stop_with_this_process(pid)
