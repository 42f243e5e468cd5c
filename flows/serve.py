"""Scheduled builds: the build flow served as a Prefect deployment.

Prefect cannot schedule on its temporary in-process server, so when no ``PREFECT_API_URL``
is set, :func:`serve_build` starts a local Prefect server (SQLite, loopback) in a child
process, waits until it answers, serves the deployment against it, and stops it on exit;
a reaper (:mod:`handdb_flows.reaper`) stops it when this process is killed.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from fsspec.core import url_to_fs
from fsspec.implementations.local import LocalFileSystem
from handdb_flows.reaper import stop_with_this_process

#: Seconds to wait for a local Prefect server to answer its health check.
SERVER_STARTUP_TIMEOUT_S = 120.0
#: Seconds to wait for the server to stop before it is killed.
SERVER_SHUTDOWN_TIMEOUT_S = 15.0
DEPLOYMENT_NAME = "handdb-build"
#: Scheduled builds run one at a time: a run due while another builds waits for it.
CONCURRENT_BUILDS = 1


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _wait_healthy(api_url: str, process: subprocess.Popen, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"the local Prefect server exited with status {process.returncode}")
        try:
            with urllib.request.urlopen(f"{api_url}/health", timeout=2) as response:
                if response.status == 200:
                    return
        except (urllib.error.URLError, ConnectionError, TimeoutError):
            pass
        time.sleep(0.5)
    raise TimeoutError(f"the local Prefect server at {api_url} did not answer within "
                       f"{timeout:.0f} s")


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(f"stopped by signal {signal.Signals(signum).name}")


@contextlib.contextmanager
def stop_on_sigterm() -> Iterator[None]:
    """Treat SIGTERM like Ctrl-C for the block, so its clean-up runs (the local server stops).

    Prefect's runner handles SIGTERM itself once it serves; this covers the time before,
    while the local server starts.
    """
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def prefect_api() -> Iterator[str]:
    """Yield the Prefect API URL to serve against, starting a local server if none is set."""
    existing = os.environ.get("PREFECT_API_URL")
    if existing:
        yield existing
        return
    port = _free_port()
    api_url = f"http://127.0.0.1:{port}/api"
    env = {k: v for k, v in os.environ.items() if k != "PREFECT_API_URL"}
    process = subprocess.Popen(
        [sys.executable, "-m", "prefect", "server", "start", "--host", "127.0.0.1",
         "--port", str(port)],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    stop_with_this_process(process.pid)
    try:
        _wait_healthy(api_url, process, SERVER_STARTUP_TIMEOUT_S)
        os.environ["PREFECT_API_URL"] = api_url
        yield api_url
    finally:
        os.environ.pop("PREFECT_API_URL", None)
        process.terminate()
        try:
            process.wait(SERVER_SHUTDOWN_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def absolute_location(location: str) -> str:
    """``location`` with a local path made absolute; a URL as it is."""
    fs, _ = url_to_fs(location)
    return str(Path(location).resolve()) if isinstance(fs, LocalFileSystem) else location


def deployment_settings(inbox: str, db: str) -> dict[str, Any]:
    """The served deployment's name, description and parameters, as ``Flow.serve`` takes them.

    The description is the flow's markdown one (:data:`handdb_flows.build.DESCRIPTION`),
    not its docstring, whose reStructuredText the Prefect UI would show raw; local paths
    are made absolute, since scheduled runs start in another working folder.
    """
    from handdb_flows.build import DESCRIPTION

    return {"name": DEPLOYMENT_NAME, "description": DESCRIPTION,
            "parameters": {"inbox": absolute_location(inbox), "db": absolute_location(db)}}


def serve_build(inbox: str, db: str, *, cron: str | None = None,
                interval: float | None = None) -> None:
    """Serve the build of ``inbox`` into ``db`` on a cron or interval schedule until stopped.

    Stops on Ctrl-C or SIGTERM, and then stops the local Prefect server it started.
    """
    from handdb_flows.build import build
    from prefect.settings import PREFECT_API_URL, temporary_settings

    settings = deployment_settings(inbox, db)
    with stop_on_sigterm(), prefect_api() as api_url, \
            temporary_settings({PREFECT_API_URL: api_url}):
        build.serve(**settings, cron=cron, interval=interval, pause_on_shutdown=False,
                    print_starting_message=True, limit=CONCURRENT_BUILDS)
