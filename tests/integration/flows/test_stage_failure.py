"""A stage that fails on one clip fails that clip only: the build finishes and says why."""

from handdb_flows.settings import quick_flows

from handdb.build import summary_markdown
from handdb.store.query import query
from tests.support.building import run


def test_a_failed_export_fails_its_clip_and_the_others_are_committed(inbox, tmp_path):
    db = tmp_path / "db"
    (db / "reports").mkdir(parents=True)
    (db / "reports" / "bravo").write_text("a file where bravo's report folder belongs")
    with quick_flows():
        summary = run(str(inbox), str(db), workers=2)
    assert not summary.ok and list(summary.failed) == ["bravo"]
    assert summary.failed["bravo"].startswith("export: ")
    assert "reports/bravo" in summary.failed["bravo"]
    assert sorted(summary.processed) == ["alpha", "charlie"]
    assert "| bravo |" in summary_markdown(summary)
    committed = query(str(db), "SELECT clip_id FROM clips ORDER BY clip_id")
    assert committed.column("clip_id").to_pylist() == ["alpha", "charlie"]
    status = query(str(db), "SELECT status, n_failed FROM runs").to_pylist()
    assert status == [{"status": "failed", "n_failed": 1}]
