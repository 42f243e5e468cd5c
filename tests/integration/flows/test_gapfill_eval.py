from handdb_flows.gapfill_eval import gapfill_eval
from handdb_flows.settings import quick_flows
from typer.testing import CliRunner

from handdb.cli import app
from handdb.gapfill.evaluate import RANDOM_MASK, THESIS_MASK, pooled_rmse
from handdb.gapfill.sources import DatabaseSource, SyntheticSource, summary_markdown
from handdb.store.database import Store


def test_the_flow_scores_each_clip_and_skips_incomplete_tracks(demo_db, tmp_path):
    db = str(tmp_path / "db")
    sources = [SyntheticSource("rapid", 100, seed=1), DatabaseSource(demo_db, "wave-s02")]
    with quick_flows():
        summary = gapfill_eval(sources, db, [THESIS_MASK], ["previous", "auto"])
    assert list(summary.charts) == ["synthetic-rapid-seed1"]
    assert summary.skipped == ["wave-s02"]
    assert Store(db).read_table("gapfill_eval").equals(summary.table)
    report = summary_markdown(summary)
    rmse = pooled_rmse(summary.table)
    assert f"| auto | offline | {rmse[(THESIS_MASK, 'auto')]:.2f} |" in report
    assert "wave-s02" in report


def test_the_command_evaluates_the_database_clips_with_complete_tracks(demo_db):
    result = CliRunner().invoke(app, ["gapfill-eval", "--db", demo_db, "--method", "previous",
                                      "--method", "auto"])
    assert result.exit_code == 0, result.output
    store = Store(demo_db)
    rows = store.read("gapfill_eval", "rapid-s01")
    assert set(rows.column("mask").to_pylist()) == {THESIS_MASK, RANDOM_MASK}
    assert store.read("gapfill_eval", "wave-s02") is None
    assert store.fs.exists(store.path("reports", "rapid-s01", "gapfill.png"))
