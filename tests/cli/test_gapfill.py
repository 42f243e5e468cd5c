import json

import pyarrow.parquet as pq
from typer.testing import CliRunner

from handdb.cli.gapfill import app
from handdb.readers import tracks_csv, truth_csv
from handdb.skeletons import load_skeleton
from handdb.synthetic.clips import synthesize_clip


def test_gapfill_eval_on_synthetic_clips_prints_and_writes(tmp_path):
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--synthetic", "rapid", "--frames", "100", "--seeds", "1",
        "--mask", "thesis-table-4.2", "--method", "previous", "--method", "auto",
        "--out", str(tmp_path),
    ])
    assert result.exit_code == 0, result.output
    assert "previous" in result.output and "auto" in result.output
    table = pq.read_table(tmp_path / "gapfill_eval.parquet")
    assert set(table.column("method").to_pylist()) == {"previous", "auto"}
    assert (tmp_path / "rapid-0_thesis-table-4.2.png").is_file()


def test_gapfill_eval_refuses_an_unknown_method(tmp_path):
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--synthetic", "rapid", "--method", "magic", "--out", str(tmp_path)])
    assert result.exit_code != 0
    assert "magic" in result.output


def test_gapfill_eval_skips_an_inbox_without_complete_tracks(tmp_path):
    result = CliRunner().invoke(app, ["gapfill-eval", "--inbox", str(tmp_path),
                                      "--out", str(tmp_path / "out")])
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
    result = CliRunner().invoke(app, [
        "gapfill-eval", "--inbox", str(inbox), "--mask", "occlusion", "--mask", "random-gaps",
        "--method", "linear", "--method", "auto", "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    table = pq.read_table(tmp_path / "out" / "gapfill_eval.parquet")
    assert set(table.column("mask").to_pylist()) == {"occlusion", "random-gaps"}
    assert set(table.column("clip_id").to_pylist()) == {"fist"}
