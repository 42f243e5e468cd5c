"""What a build starts ends with it, even when the build is killed with SIGKILL."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from tests.support.paths import REPO

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(),
                                reason="reads process states from /proc")

#: Seconds a stopped process may take to be gone.
GONE_WITHIN_S = 15.0

#: A process that starts a child to be reaped, prints its pid, then waits to be killed.
PARENT = textwrap.dedent("""
    import subprocess, sys, time
    from handdb_flows.reaper import stop_with_this_process
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    stop_with_this_process(child.pid)
    print(child.pid, flush=True)
    if sys.argv[1] == "wait":
        time.sleep(120)
""")

#: A process that starts Prefect's temporary server as a build does, prints its pid, waits.
BUILD = textwrap.dedent("""
    import time
    from handdb_flows.settings import shared_api
    from prefect.server.api.server import SubprocessASGIServer
    with shared_api():
        print(SubprocessASGIServer().server_process.pid, flush=True)
        time.sleep(300)
""")


def running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has ended)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def gone(pid: int) -> bool:
    deadline = time.monotonic() + GONE_WITHIN_S
    while running(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not running(pid)


def start(code: str, *args: str) -> tuple[subprocess.Popen, int]:
    process = subprocess.Popen([sys.executable, "-c", code, *args], cwd=REPO,
                               stdout=subprocess.PIPE, start_new_session=True)
    return process, int(process.stdout.readline())


def test_a_killed_process_takes_what_it_started_with_it():
    parent, child = start(PARENT, "wait")
    assert running(child)
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    assert gone(child)


def test_a_process_that_exits_normally_releases_its_reaper():
    parent, child = start(PARENT, "exit")
    assert parent.wait(GONE_WITHIN_S) == 0
    try:
        time.sleep(0.5)
        assert running(child)  # the reaper was told the exit was normal: stopping is not its job
    finally:
        os.kill(child, signal.SIGKILL)


@pytest.mark.slow
def test_a_killed_build_leaves_no_temporary_prefect_server():
    build, server = start(BUILD)
    assert running(server)
    os.kill(build.pid, signal.SIGKILL)
    build.wait()
    assert gone(server)
