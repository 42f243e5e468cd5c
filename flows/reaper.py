"""Stop a server a build started when the build dies, however it dies (even by SIGKILL).

:func:`stop_with_this_process` starts this file as a script, with the server's pid, in a
session of its own (a Ctrl-C at the terminal does not reach it). The reaper reads its
standard input, a pipe from this process, until the pipe closes. The pipe closes when this
process ends, whatever ends it: the kernel closes it. On a normal exit this process first
writes :data:`RELEASE`, and its own shutdown stops the server (Prefect stops its temporary
server at exit); when the pipe closes without that word, this process was killed, and the
reaper terminates the server, then kills it if it has not ended within :data:`GRACE_S`.
The server is still this process's orphan then, so its pid names it. The script imports
only the standard library, so it starts in milliseconds and holds little memory.
"""

from __future__ import annotations

import atexit
import os
import signal
import subprocess
import sys
import time

#: What this process writes to the reaper when it exits normally.
RELEASE = b"release\n"

#: Seconds the server has to stop after SIGTERM before it is killed.
GRACE_S = 5.0

#: Seconds between checks that the server has stopped.
POLL_S = 0.05

#: Signal that ends a server ignoring SIGTERM (Windows has none: terminating is killing).
_KILL = getattr(signal, "SIGKILL", signal.SIGTERM)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` still exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def stop(pid: int) -> None:
    """Terminate process ``pid``; kill it if it is still there after :data:`GRACE_S`."""
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    deadline = time.monotonic() + GRACE_S
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(POLL_S)
    if _alive(pid):
        try:
            os.kill(pid, _KILL)
        except ProcessLookupError:
            return


def _release(reaper: subprocess.Popen) -> None:
    """Tell the reaper this process exits normally, and wait for it to end."""
    assert reaper.stdin is not None, "the reaper is started with a pipe to its input"
    try:
        reaper.stdin.write(RELEASE)
        reaper.stdin.close()
    except OSError:
        return
    reaper.wait(GRACE_S)


def stop_with_this_process(pid: int) -> subprocess.Popen:
    """Make sure process ``pid`` ends when this process does, even when this one is killed.

    Call it right after starting the process, and after whatever stops it at exit was
    registered (``atexit`` runs the release first). Returns the reaper.
    """
    reaper = subprocess.Popen([sys.executable, "-I", os.path.abspath(__file__), str(pid)],
                              stdin=subprocess.PIPE, start_new_session=True)
    atexit.register(_release, reaper)
    return reaper


def main(argv: list[str]) -> None:
    """Wait until the process at the other end of standard input ends; stop ``argv[1]``."""
    pid = int(argv[1])
    if sys.stdin.buffer.read() != RELEASE:
        stop(pid)


if __name__ == "__main__":
    main(sys.argv)
