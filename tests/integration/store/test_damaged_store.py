"""A damaged store on a real build: what a committed clip needs is checked, and what is
missing or damaged is rebuilt from the inbox, saying so."""

import pytest

from handdb.build import BuildOptions, build_in_process
from handdb.store.query import query

OPTIONS = BuildOptions(export_usd=False)


@pytest.fixture
def built(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    for seed, clip_id in enumerate(["alpha", "bravo"]):
        write_clip(inbox, clip_id, seed=seed)
    db = tmp_path / "db"
    assert sorted(build_in_process(inbox, str(db), OPTIONS).processed) == ["alpha", "bravo"]
    rows = query(str(db), "SELECT clip_id, count(*) AS n FROM joints_3d GROUP BY clip_id "
                 "ORDER BY clip_id").to_pylist()
    return inbox, db, rows


def _cut(path):
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])


@pytest.mark.parametrize(("file", "damage", "said"), [
    ("joints_3d/alpha.parquet", lambda p: p.unlink(), "joints_3d/alpha.parquet is missing"),
    ("joints_3d/alpha.parquet", _cut, "joints_3d/alpha.parquet is damaged"),
    ("clips/alpha.parquet", _cut, "clips/alpha.parquet is damaged"),
])
def test_a_damaged_clip_is_rebuilt_from_the_inbox(built, file, damage, said):
    inbox, db, rows = built
    damage(db / file)
    summary = build_in_process(inbox, str(db), OPTIONS)
    assert summary.processed == ["alpha"] and summary.unchanged == ["bravo"]
    [repair] = summary.repairs
    assert repair.startswith(f"clip alpha: {said}") and repair.endswith("; rebuilt from the inbox")
    after = query(str(db), "SELECT clip_id, count(*) AS n FROM joints_3d GROUP BY clip_id "
                  "ORDER BY clip_id").to_pylist()
    assert after == rows
    again = build_in_process(inbox, str(db), OPTIONS)
    assert again.processed == [] and again.repairs == ()


def test_a_damaged_quarantine_file_is_written_again(built, write_clip):
    inbox, db, _ = built
    (inbox / "broken.clip.json").write_text("{")
    (inbox / "broken.tracks.csv").write_text("frame,joint,u,v\n")
    first = build_in_process(inbox, str(db), OPTIONS)
    assert [r.clip_id for r in first.refusals] == ["broken"]
    _cut(db / "quarantine" / "quarantine.parquet")
    summary = build_in_process(inbox, str(db), OPTIONS)
    assert len(summary.repairs) == 1 and "quarantine.parquet is damaged" in summary.repairs[0]
    stored = query(str(db), "SELECT clip_id FROM quarantine").to_pylist()
    assert stored == [{"clip_id": "broken"}]


def test_a_missing_usd_file_is_written_again(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=0)
    db = tmp_path / "db"
    build_in_process(inbox, str(db), BuildOptions())
    usd = db / "usd" / "alpha.usd"
    committed = usd.read_bytes()
    usd.unlink()
    summary = build_in_process(inbox, str(db), BuildOptions())
    assert summary.repairs == ("clip alpha: usd/alpha.usd is missing; rebuilt from the inbox",)
    assert summary.processed == ["alpha"] and len(usd.read_bytes()) == len(committed)
