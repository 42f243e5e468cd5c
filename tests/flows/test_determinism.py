"""Same inputs, same database: every file but the run log is identical byte for byte."""

import hashlib
from pathlib import Path

from handdb_flows.build import run
from handdb_flows.settings import quick_flows


def file_digests(db: Path) -> dict[str, str]:
    """SHA-256 of every file of the database except the run log and the lock."""
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*"))
        if path.is_file() and path.parent.name != "runs" and path.name != ".lock"
    }


def test_two_fresh_databases_are_identical_whatever_the_parallelism(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=1)
    write_clip(inbox, "bravo", seed=2, fmt="dlc")
    with quick_flows():
        first = run(str(inbox), str(tmp_path / "one"), workers=1)
        second = run(str(inbox), str(tmp_path / "two"), workers=3)
    assert sorted(first.processed) == sorted(second.processed) == ["alpha", "bravo"]
    one, two = file_digests(tmp_path / "one"), file_digests(tmp_path / "two")
    kinds = {Path(name).suffix for name in one}
    assert {".parquet", ".usd", ".png"} <= kinds
    assert one == two
