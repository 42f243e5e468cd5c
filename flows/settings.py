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
    get_current_settings,
    temporary_settings,
)

#: API URLs of the temporary servers :func:`shared_api` started; they end with this process.
_TEMPORARY_APIS: set[str] = set()


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
    assert server.server_process is not None, "a started server has its process"
    _reaped(server.server_process.pid)
    _TEMPORARY_APIS.add(server.api_url)
    with temporary_settings({PREFECT_API_URL: server.api_url}):
        yield server.api_url


@cache
def _reaped(pid: int) -> subprocess.Popen:
    """The reaper of process ``pid``, started once however often the server is reused."""
    return stop_with_this_process(pid)


def lasting_run_url() -> str | None:
    """The page of the current flow run in the Prefect UI, if it outlives this process.

    That is when ``PREFECT_UI_URL`` is set, or when the API is a server of its own
    (``PREFECT_API_URL``, as ``handdb serve`` sets it); a temporary server started for one
    build (:func:`shared_api`), or Prefect's in-process one, stops with the build, and a
    link to it would lead nowhere. ``None`` outside a flow run.
    """
    from prefect.runtime import flow_run

    api_url = PREFECT_API_URL.value()
    # Prefect fills in a UI URL from the API URL, but leaves it out of the fields set.
    ui_url_set = "ui_url" in get_current_settings().model_fields_set
    if ui_url_set or (api_url and api_url not in _TEMPORARY_APIS):
        return flow_run.ui_url
    return None
