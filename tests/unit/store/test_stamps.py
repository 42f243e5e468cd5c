"""Digests taken from files' stamps: reused while a file is unchanged, never once it changed."""

import os
import time

import pytest

from handdb.build import BuildOptions, build_in_process, plan_build
from handdb.build import plan as build_plan
from handdb.store import stamps
from handdb.store.database import Store
from tests.support.store_rows import clip_row, truth_rows

OPTIONS = BuildOptions(export_usd=False)


@pytest.fixture
def settle_at_once(monkeypatch):
    """Files count as settled as soon as they were written (a build cannot wait seconds)."""
    monkeypatch.setattr(stamps, "SETTLED_NS", 0)


def _later() -> int:
    """A moment well after every file of a test was written, in nanoseconds."""
    return time.time_ns() + 10 * stamps.SETTLED_NS


def _rewrite_in_place(path, data: bytes) -> None:
    """Write ``data`` over ``path`` and give it back its modification time."""
    before = path.stat()
    path.write_bytes(data)
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))


def _calls(monkeypatch, owner, name: str) -> list[tuple]:
    """The arguments of every call of ``owner.name`` from now on."""
    calls: list[tuple] = []
    original = getattr(owner, name)

    def counted(*args):
        calls.append(args)
        return original(*args)

    monkeypatch.setattr(owner, name, counted)
    return calls


def test_a_settled_digest_stands_until_its_file_changes(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"abcd")
    files = [str(path)]
    entry = stamps.entry_if_settled(files, [stamps.stamp(str(path))], "digest", _later())
    known = {stamps.entry_key(files): entry}
    assert stamps.known_digest(known, files) == "digest"
    assert stamps.known_digest(known, files, scope="another inbox") is None
    _rewrite_in_place(path, b"abce")
    assert path.stat().st_size == 4
    assert stamps.known_digest(known, files) is None


def test_a_file_written_just_now_gets_no_entry(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"abcd")
    assert stamps.entry_if_settled([str(path)], [stamps.stamp(str(path))], "digest",
                                   time.time_ns()) is None
    assert stamps.entry_if_settled([str(path)], [None], "digest", _later()) is None


def test_entries_are_kept_and_a_damaged_file_of_them_is_no_entry(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"abcd")
    entry = stamps.entry_if_settled([str(path)], [stamps.stamp(str(path))], "digest", _later())
    kept = tmp_path / stamps.STAMPS_FILE
    stamps.save_stamps(str(kept), {"key": entry})
    assert stamps.load_stamps(str(kept)) == {"key": entry}
    kept.write_text('{"key": {"files": [1]')
    assert stamps.load_stamps(str(kept)) == {}


def test_entries_of_another_version_are_no_entry(tmp_path, monkeypatch):
    path = tmp_path / "a.bin"
    path.write_bytes(b"abcd")
    entry = stamps.entry_if_settled([str(path)], [stamps.stamp(str(path))], "digest", _later())
    kept = tmp_path / stamps.STAMPS_FILE
    stamps.save_stamps(str(kept), {"key": entry})
    monkeypatch.setattr(stamps, "STAMPS_VERSION", stamps.STAMPS_VERSION + 1)
    assert stamps.load_stamps(str(kept)) == {}


def test_a_stored_file_damaged_in_place_is_noticed_despite_its_stamp(tmp_path, settle_at_once):
    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 3)})
    damage, known = store.checked_clip_files("a", {})
    assert damage is None and len(known) == 2
    assert store.checked_clip_files("a", known) == (None, known)
    stored = tmp_path / "db" / "truth_3d" / "a.parquet"
    data = bytearray(stored.read_bytes())
    data[len(data) // 2] ^= 0xFF
    _rewrite_in_place(stored, bytes(data))
    damage, _ = store.checked_clip_files("a", known)
    assert damage == "truth_3d/a.parquet is damaged (its checksum differs from the commit's)"


def test_a_rebuild_hashes_only_what_changed(tmp_path, write_clip, settle_at_once, monkeypatch):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    for seed, clip_id in enumerate(["alpha", "bravo"]):
        write_clip(inbox, clip_id, seed=seed)
    assert sorted(build_in_process(inbox, db, OPTIONS).processed) == ["alpha", "bravo"]
    stored_hashed = _calls(monkeypatch, Store, "_fingerprint")
    inbox_hashed = _calls(monkeypatch, build_plan, "clip_content_hash")
    again = build_in_process(inbox, db, OPTIONS)
    assert again.processed == [] and stored_hashed == [] and inbox_hashed == []
    track = inbox / "alpha.tracks.csv"
    text = track.read_text()
    _rewrite_in_place(track, text.replace("0.9", "0.8", 1).encode())
    assert [c.clip_id for c in plan_build(inbox, db, OPTIONS).todo] == ["alpha"]
    assert [entry.clip_id for entry, in inbox_hashed] == ["alpha"]
