"""A database on an fsspec URL: the build writes there and DuckDB reads it there.

``memory://`` stands in for an object store (it lives in this process only, so the flow
runs in-process); ``file://`` is the local filesystem behind a URL.
"""

import hashlib
import os
import tempfile
import uuid
from pathlib import Path

import fsspec
import pytest
from handdb_flows.settings import quick_flows

import handdb
from handdb.errors import DatabaseLockedError
from handdb.store.database import LOCK_FILE, Store
from handdb.store.stamps import STAMPS_FILE
from tests.support.building import run


def build(inbox: Path, db: str):
    with quick_flows():
        return run(str(inbox), db, workers=2)


def url_digests(url: str) -> dict[str, str]:
    """SHA-256 of every file under ``url`` but the run log, the lock and the stamps (a local
    folder's cache of what was hashed, :mod:`handdb.store.stamps`), by relative path."""
    fs, root = fsspec.core.url_to_fs(url)
    root = root.rstrip("/")
    return {
        path[len(root) + 1:]: hashlib.sha256(fs.cat_file(path)).hexdigest()
        for path in fs.find(root)
        if "/runs/" not in path and not path.endswith((LOCK_FILE, STAMPS_FILE))
    }


@pytest.fixture
def one_clip_inbox(tmp_path, write_clip) -> Path:
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=4)
    return inbox


@pytest.fixture
def memory_db():
    url = f"memory://handdb-{uuid.uuid4().hex}/db"
    yield url
    fs, root = fsspec.core.url_to_fs(url)
    fs.rm(root.split("/")[1], recursive=True)


def test_memory_and_file_urls_hold_the_same_bytes_as_a_folder(one_clip_inbox, tmp_path,
                                                               memory_db, n_frames):
    folder = tmp_path / "folder-db"
    file_url = (tmp_path / "url-db").as_uri()
    for db in (str(folder), memory_db, file_url):
        summary = build(one_clip_inbox, db)
        assert summary.ok and summary.processed == ["alpha"]
    expected = url_digests(str(folder))
    assert {"usd/alpha.usd", "reports/alpha/preview.png", "clips/alpha.parquet"} <= set(expected)
    assert url_digests(memory_db) == expected
    assert url_digests(file_url) == expected
    for db in (memory_db, file_url):
        with handdb.connect(db) as con:
            rows = con.execute("SELECT count(*), count(DISTINCT frame) FROM joints_3d "
                           "JOIN clips USING (clip_id) WHERE usd_path = 'usd/alpha.usd'"
                           ).fetchone()
        assert rows == (n_frames * 21, n_frames)


def test_a_rebuild_on_a_url_changes_nothing(one_clip_inbox, memory_db):
    build(one_clip_inbox, memory_db)
    before = url_digests(memory_db)
    summary = build(one_clip_inbox, memory_db)
    assert summary.unchanged == ["alpha"] and summary.processed == []
    assert url_digests(memory_db) == before
    assert handdb.connect(memory_db).execute("SELECT count(*) FROM runs").fetchone() == (2,)


def test_a_lock_file_left_on_a_url_refuses_the_build_and_names_itself(one_clip_inbox,
                                                                       memory_db):
    store = Store(memory_db)
    store.fs.makedirs(store.root, exist_ok=True)
    store.fs.pipe_file(store.path(LOCK_FILE), b"pid 1 on elsewhere")
    with pytest.raises(DatabaseLockedError, match=f"{LOCK_FILE}.*remove the file"):
        build(one_clip_inbox, memory_db)
    assert store.table_files("clips") == []


def test_exports_reach_a_database_on_another_device(one_clip_inbox, tmp_path, monkeypatch):
    scratch = Path("/dev/shm")
    if not scratch.is_dir() or os.stat(scratch).st_dev == os.stat(tmp_path).st_dev:
        pytest.skip("no second filesystem to hold scratch files")
    with tempfile.TemporaryDirectory(dir=scratch) as other_device:
        monkeypatch.setattr(tempfile, "tempdir", other_device)
        summary = build(one_clip_inbox, str(tmp_path / "db"))
    assert summary.ok, summary.failed
    assert (tmp_path / "db" / "usd" / "alpha.usd").stat().st_size > 0
