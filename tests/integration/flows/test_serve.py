"""``handdb serve --interval``: a clip dropped into the inbox reaches the tables at a
scheduled run, against the local Prefect server serve starts, which stops with it."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from handdb.store.query import query
from tests.support.paths import REPO

pytestmark = pytest.mark.slow


#: Seconds between scheduled builds.
INTERVAL_S = 5
#: Seconds to wait for each awaited event (server start, a scheduled run, shutdown).
WAIT_S = 240.0


def wait_for(condition, what: str, process: subprocess.Popen, log: Path) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition():
        assert process.poll() is None, f"serve exited early:\n{log.read_text()}"
        assert time.monotonic() < deadline, f"no {what} within {WAIT_S:.0f} s:\n{log.read_text()}"
        time.sleep(1.0)


def session_processes(session_id: int) -> list[int]:
    """Pids of live processes in the session ``session_id`` (field 6 of /proc/<pid>/stat)."""
    pids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == session_id and fields[0] != "Z":
            pids.append(int(stat.parent.name))
    return pids


def clip_ids(db: Path) -> list[str]:
    if not (db / "clips").is_dir():
        return []
    return query(str(db), "SELECT clip_id FROM clips").column("clip_id").to_pylist()


def n_runs(db: Path) -> int:
    if not (db / "runs").is_dir():
        return 0
    return query(str(db), "SELECT count(*) AS n FROM runs").column("n")[0].as_py()


def test_served_build_picks_up_a_dropped_clip_and_stops_its_server(tmp_path, write_clip):
    inbox, db, log = tmp_path / "inbox", tmp_path / "db", tmp_path / "serve.log"
    inbox.mkdir()
    env = {k: v for k, v in os.environ.items() if k != "PREFECT_API_URL"}
    # a new Prefect home: no runs scheduled by an earlier session wait on its server
    env["PREFECT_HOME"] = str(tmp_path / "prefect")
    with log.open("wb") as out:
        serve = subprocess.Popen(
            [sys.executable, "-c", "from handdb.cli import main; main()", "serve",
             "--inbox", str(inbox), "--db", str(db), "--interval", str(INTERVAL_S)],
            cwd=REPO, env=env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_for(lambda: n_runs(db) > 0, "scheduled run", serve, log)
        assert clip_ids(db) == []
        write_clip(inbox, "dropped", seed=3)
        wait_for(lambda: clip_ids(db) == ["dropped"], "run with the dropped clip", serve, log)
        assert len(session_processes(serve.pid)) >= 2, "serve runs no Prefect server"
        serve.send_signal(signal.SIGTERM)
        assert serve.wait(WAIT_S) is not None
        deadline = time.monotonic() + WAIT_S
        while session_processes(serve.pid) and time.monotonic() < deadline:
            time.sleep(1.0)
        assert session_processes(serve.pid) == [], log.read_text()
    finally:
        if serve.poll() is None or session_processes(serve.pid):
            os.killpg(serve.pid, signal.SIGKILL)
