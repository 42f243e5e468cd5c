"""Same inputs, same database: every file but the run log is identical byte for byte,
in this process or in Prefect tasks, one clip at a time or several."""

import hashlib
from pathlib import Path

from tests.support.building import run


def file_digests(db: Path) -> dict[str, str]:
    """SHA-256 of every file of the database except the run log and the lock."""
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*"))
        if path.is_file() and path.parent.name != "runs" and path.name != ".lock"
    }


def test_two_fresh_databases_are_identical_whatever_runs_them(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=1)
    write_clip(inbox, "bravo", seed=2, fmt="dlc")
    first = run(str(inbox), str(tmp_path / "one"), workers=1, runner="local")
    second = run(str(inbox), str(tmp_path / "two"), workers=3, runner="thread")
    assert sorted(first.processed) == sorted(second.processed) == ["alpha", "bravo"]
    one, two = file_digests(tmp_path / "one"), file_digests(tmp_path / "two")
    kinds = {Path(name).suffix for name in one}
    assert {".parquet", ".usd", ".png"} <= kinds
    assert one == two
