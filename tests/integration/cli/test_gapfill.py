import json

import pyarrow.parquet as pq
from typer.testing import CliRunner

from handdb.cli import app
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import tracks_csv, truth_csv
from handdb.store.database import Store
from handdb.synthetic.clips import synthesize_clip


def test_gapfill_eval_on_synthetic_clips_writes_the_database_and_a_folder(tmp_path):
    db = str(tmp_path / "db")
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--synthetic", "rapid", "--frames", "100", "--seeds", "1",
        "--mask", "thesis-table-4.2", "--method", "previous", "--method", "auto",
        "--db", db, "--out", str(tmp_path / "out"),
    ])
    assert result.exit_code == 0, result.output
    assert "previous" in result.output and "auto" in result.output
    rows = Store(db).read("gapfill_eval", "synthetic-rapid-seed0")
    assert set(rows.column("method").to_pylist()) == {"previous", "auto"}
    assert (tmp_path / "db" / "reports" / "synthetic-rapid-seed0" / "gapfill.png").is_file()
    table = pq.read_table(tmp_path / "out" / "gapfill_eval.parquet")
    assert table.equals(rows)
    assert (tmp_path / "out" / "synthetic-rapid-seed0_gapfill.png").is_file()


def test_gapfill_eval_refuses_an_unknown_method(tmp_path):
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--synthetic", "rapid", "--method", "magic", "--db", str(tmp_path)])
    assert result.exit_code != 0
    assert "magic" in result.output


def test_gapfill_eval_skips_an_inbox_without_complete_tracks(tmp_path):
    result = CliRunner().invoke(app, ["gapfill-eval", "--inbox", str(tmp_path),
                                      "--db", str(tmp_path / "db")])
    assert result.exit_code == 1
    assert "no clip with complete tracks" in result.output


def test_gapfill_eval_on_an_inbox_clip_with_truth(tmp_path):
    skeleton = load_skeleton("mediapipe21")
    clip = synthesize_clip("clench", 12, seed=0)
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    (inbox / "fist.clip.json").write_text(json.dumps({
        "skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
        "units": "mm", "camera": {"model": "orthographic"}}))
    tracks_csv.write(inbox / "fist.tracks.csv", clip.uv, None, skeleton)
    truth_csv.write(inbox / "fist.truth.csv", clip.xyz, skeleton)
    db = str(tmp_path / "db")
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--inbox", str(inbox), "--mask", "occlusion", "--mask", "random-gaps",
        "--method", "linear", "--method", "auto", "--db", db])
    assert result.exit_code == 0, result.output
    table = Store(db).read_table("gapfill_eval")
    assert set(table.column("mask").to_pylist()) == {"occlusion", "random-gaps"}
    assert set(table.column("clip_id").to_pylist()) == {"fist"}
