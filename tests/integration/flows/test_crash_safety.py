"""Crash safety: builds killed with SIGKILL and run again end with an uninterrupted
build's tables; two builds started at once on one database leave it whole.

Builds run as ``handdb build`` subprocesses (each in its own session, so the kill also
takes the temporary Prefect server it started) on a small inbox with an X-ray file and a
bad clip. Every file of the database is compared byte for byte with an uninterrupted
build's, except the run log (``runs``: one row per run, killed runs leave none), the time
column of ``quarantine`` and the ``build_key`` column of ``clips``: it hashes handdb's
source, which other work may change between the reference build and the last one here
(``test_determinism.py`` compares ``clips`` files byte for byte).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

from handdb.store.database import LOCK_FILE
from handdb.store.query import query
from handdb.store.stamps import STAMPS_FILE
from tests.support.paths import REPO

pytestmark = pytest.mark.slow


CLIP_IDS = ("alpha", "bravo", "charlie", "delta", "echo", "foxtrot")
#: Seconds a build subprocess may take before the test gives up on it.
BUILD_TIMEOUT_S = 600.0
POLL_S = 0.02
#: Seed of the random kill delay, and the share of an uninterrupted build it falls in.
KILL_SEED = 7
KILL_SHARE = (0.1, 0.7)


def database_digests(db: Path) -> dict[str, str]:
    """SHA-256 of every file but the run log, the lock, the stamps, ``quarantine``, ``clips``.

    The stamps (:mod:`handdb.store.stamps`) are a cache of what was hashed when, not content.
    """
    skipped = {"runs", "quarantine", "clips"}
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*"))
        if path.is_file() and path.parent.name not in skipped
        and path.name not in (LOCK_FILE, STAMPS_FILE)
    }


def table_rows(db: Path) -> dict[str, list[dict]]:
    """Rows of ``clips`` and ``quarantine``, without the columns that may differ."""
    return {
        "clips": query(str(db), "SELECT * EXCLUDE (build_key) FROM clips ORDER BY clip_id"
                       ).to_pylist(),
        "quarantine": query(str(db), "SELECT * EXCLUDE (time) FROM quarantine ORDER BY ALL"
                            ).to_pylist(),
    }


def prefect_home(name: str) -> str:
    """A Prefect home kept between test runs (a new one costs a database migration)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    home = REPO / ".prefect" / f"test-{worker}-{name}"
    home.mkdir(parents=True, exist_ok=True)
    return str(home)


def start_build(inbox: Path, db: Path, log: Path, home: str) -> subprocess.Popen:
    """Start ``handdb build`` in a new session; its output goes to ``log``."""
    env = {k: v for k, v in os.environ.items() if k != "PREFECT_API_URL"}
    env["PREFECT_HOME"] = home
    with log.open("wb") as out:
        return subprocess.Popen(
            [sys.executable, "-c", "from handdb.cli import main; main()", "build",
             "--inbox", str(inbox), "--db", str(db), "--workers", "2"],
            cwd=REPO, env=env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)


def kill_when(process: subprocess.Popen, ready: Callable[[], bool]) -> None:
    """SIGKILL the process and its session as soon as ``ready()``; fail if it ends first."""
    deadline = time.monotonic() + BUILD_TIMEOUT_S
    while not ready():
        assert process.poll() is None, "the build finished before the kill point"
        assert time.monotonic() < deadline, "the kill point never came"
        time.sleep(POLL_S)
    os.killpg(process.pid, signal.SIGKILL)
    assert process.wait(BUILD_TIMEOUT_S) == -signal.SIGKILL


def n_files(db: Path, table: str) -> int:
    return len(list((db / table).glob("*.parquet")))


def new_file_in(table: str) -> Callable[[Path, int], Callable[[], bool]]:
    """Kill point: a file of ``table`` that was not there when the build started."""
    def point(db: Path, pid: int) -> Callable[[], bool]:
        before = n_files(db, table)
        return lambda: n_files(db, table) > before
    return point


def seconds_into_build(delay: float) -> Callable[[Path, int], Callable[[], bool]]:
    """Kill point: ``delay`` seconds after the build took the database's lock."""
    def point(db: Path, pid: int) -> Callable[[], bool]:
        lock, locked_at = db / LOCK_FILE, []

        def ready() -> bool:
            if not locked_at and lock.is_file() and \
                    lock.read_text().startswith(f"pid {pid} "):
                locked_at.append(time.monotonic())
            return bool(locked_at) and time.monotonic() - locked_at[0] >= delay
        return ready
    return point


@pytest.fixture(scope="module")
def inbox(tmp_path_factory, write_clip) -> Path:
    path = tmp_path_factory.mktemp("crash") / "inbox"
    path.mkdir()
    for seed, clip_id in enumerate(CLIP_IDS):
        write_clip(path, clip_id, seed=seed)
    shutil.copyfile(str(files("handdb") / "data" / "chaudhry_table1.xray.csv"),
                    path / "chaudhry_table1.xray.csv")
    (path / "broken.clip.json").write_text('{"skeleton": "mediapipe21", "fps": 30}')
    (path / "broken.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")
    return path


@dataclass(frozen=True)
class Reference:
    """An uninterrupted build of the inbox: its database and how long it held the lock (s)."""

    db: Path
    seconds: float


@pytest.fixture(scope="module")
def reference(inbox, tmp_path_factory) -> Reference:
    folder = tmp_path_factory.mktemp("reference")
    db = folder / "db"
    process = start_build(inbox, db, folder / "build.log", prefect_home("reference"))
    locked = seconds_into_build(0.0)(db, process.pid)
    while not locked() and process.poll() is None:
        time.sleep(POLL_S)
    start = time.monotonic()
    assert process.wait(BUILD_TIMEOUT_S) == 3, (folder / "build.log").read_text()
    assert n_files(db, "clips") == len(CLIP_IDS) and n_files(db, "quarantine") == 1
    return Reference(db, time.monotonic() - start)


def test_builds_killed_anywhere_then_rerun_end_with_the_uninterrupted_tables(
        inbox, reference, tmp_path):
    db, timed_db = tmp_path / "db", tmp_path / "timed" / "db"
    timed_db.parent.mkdir()
    home = prefect_home("crash")
    delay = float(np.random.default_rng(KILL_SEED).uniform(*KILL_SHARE)) * reference.seconds
    kills = [
        (db, "X-ray measurements written", new_file_in("xray_measurements")),
        (db, "first clip half committed (joints_3d before clips)", new_file_in("joints_3d")),
        (db, "one more clip committed", new_file_in("clips")),
        # A random time, on a database of its own so that every clip is still to build:
        # a share of the time the uninterrupted build held the lock.
        (timed_db, f"{delay:.1f} s into the build", seconds_into_build(delay)),
    ]
    for target, name, point in kills:
        process = start_build(inbox, target, tmp_path / "killed.log", home)
        kill_when(process, point(target, process.pid))
        assert n_files(target, "clips") < len(CLIP_IDS), f"killed too late: {name}"
    remaining = len(CLIP_IDS) - n_files(db, "clips")
    for target in (db, timed_db):
        final = start_build(inbox, target, tmp_path / "final.log", home)
        assert final.wait(BUILD_TIMEOUT_S) == 3, (tmp_path / "final.log").read_text()
        assert not list(target.rglob("*.tmp"))
        assert database_digests(target) == database_digests(reference.db)
        assert table_rows(target) == table_rows(reference.db)
    # killed builds leave no runs row; the last one redid at least the uncommitted clips
    [last] = query(str(db), "SELECT n_processed, n_unchanged FROM runs").to_pylist()
    assert last["n_processed"] >= remaining
    assert last["n_processed"] + last["n_unchanged"] == len(CLIP_IDS)


def test_a_second_build_started_at_once_is_refused_and_the_first_completes(
        inbox, reference, tmp_path):
    db = tmp_path / "db"
    logs = [tmp_path / "first.log", tmp_path / "second.log"]
    builds = [start_build(inbox, db, log, prefect_home(f"lock-{i}"))
              for i, log in enumerate(logs)]
    codes = [process.wait(BUILD_TIMEOUT_S) for process in builds]
    outputs = [log.read_text() for log in logs]
    assert sorted(codes) == [1, 3], outputs
    refused = outputs[codes.index(1)]
    assert "is being built by pid" in refused and "wait for that build" in refused
    # refused by the library before Prefect starts: no flow run, no ERROR log, no traceback
    assert "ERROR" not in refused and "Traceback" not in refused, refused
    assert database_digests(db) == database_digests(reference.db)
    assert table_rows(db) == table_rows(reference.db)
    assert query(str(db), "SELECT count(*) AS n FROM runs").column("n")[0].as_py() == 1
