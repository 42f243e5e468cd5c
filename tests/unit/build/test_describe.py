"""How a build and its clips are worded for an orchestrator's run page, on real builds."""

from dataclasses import replace

from handdb.build import BuildContext, BuildOptions, build_in_process, plan_build, run_clip
from handdb.build.describe import (
    OutcomeKind,
    clip_line,
    planned_run_name,
    run_name,
    run_outcome,
    stages_run,
)
from handdb.store import query
from tests.support.building import GIANT_FACTOR, scale_bones

OPTIONS = BuildOptions(export_usd=False, gap_fill="linear")


def spoil_value(track, row: int = 5) -> None:
    lines = track.read_text().splitlines()
    frame, joint, _, v, conf = lines[row].split(",")
    lines[row] = ",".join([frame, joint, "abc", v, conf])
    track.write_text("\n".join(lines) + "\n")


def test_each_clip_line_says_what_the_build_did_with_it(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    write_clip(inbox, "fine", seed=1)
    write_clip(inbox, "giant", seed=2)
    scale_bones(inbox, "giant", GIANT_FACTOR)
    spoil_value(write_clip(inbox, "spoilt", seed=3))
    (inbox / "lost.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")

    plan = plan_build(inbox, db, OPTIONS)
    assert planned_run_name(plan) == "build 3 clips (3 to process, 1 refused)"
    context = BuildContext(inbox=str(inbox), db=db, options=OPTIONS, ratios=plan.xray.ratios)
    lines = {item.clip_id: clip_line(item, run_clip(item, context)) for item in plan.todo}
    every_stage = "ingest, lengths, gap_fill, lift, validate, export, commit"
    assert lines["fine"] == f"clip fine: ran {every_stage}; 40 frames"
    assert lines["giant"].startswith(f"clip giant: ran {every_stage}; 40 frames; flagged: ")
    assert "outside the" in lines["giant"]
    assert lines["spoilt"].startswith("clip spoilt refused: ")
    assert "spoilt.tracks.csv:6: field 'u'" in lines["spoilt"]


def test_a_rebuild_from_a_later_stage_names_only_the_stages_it_ran(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    write_clip(inbox, "solo", seed=1)
    build_in_process(inbox, db, OPTIONS)
    options = BuildOptions(export_usd=False, gap_fill="linear", lift="thesis-nocheck")
    plan = plan_build(inbox, db, options)
    (item,) = plan.todo
    assert stages_run(item) == ("lift", "validate", "export", "commit")
    context = BuildContext(inbox=str(inbox), db=db, options=options, ratios=plan.xray.ratios)
    assert clip_line(item, run_clip(item, context)) == \
        "clip solo: ran lift, validate, export, commit (earlier stages read back); 40 frames"


def test_names_and_outcomes_count_what_happened(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    write_clip(inbox, "one", seed=1)
    spoil_value(write_clip(inbox, "two", seed=2))
    first = build_in_process(inbox, db, OPTIONS)
    assert run_name(first) == "build 2 clips (1 processed, 1 refused)"
    outcome = run_outcome(first)
    assert (outcome.kind, outcome.name) == (OutcomeKind.refusals, "Completed with refusals")
    assert outcome.message == ("1 input refused (see the quarantine table); "
                               "1 of 2 clips processed, 0 unchanged")

    (inbox / "two.tracks.csv").unlink()
    (inbox / "two.clip.json").unlink()
    (inbox / "two.truth.csv").unlink()
    second = build_in_process(inbox, db, OPTIONS)
    assert run_name(second) == "build 1 clip (nothing new)"
    assert run_outcome(second).kind is OutcomeKind.completed
    assert run_outcome(second).message == "0 of 1 clip processed, 1 unchanged"
    # the quarantine emptied: the build changed the database though it processed nothing
    assert second.changed and not build_in_process(inbox, db, OPTIONS).changed

    # five of six clips failing to commit: three are named, the rest counted
    failing = replace(second, n_clips=6, failed={name: "commit: OSError: disk full"
                                                 for name in "abcde"})
    failed = run_outcome(failing)
    assert (failed.kind, failed.name) == (OutcomeKind.failed, "Failed")
    assert failed.message == ("5 of 6 clips failed (a, b, c and 2 more); "
                              "0 of 6 clips processed, 1 unchanged")
    assert run_name(failing) == "build 6 clips (5 failed)"


def test_the_local_runner_leaves_the_flow_run_columns_null(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    write_clip(inbox, "solo", seed=1)
    summary = build_in_process(inbox, db, OPTIONS)
    assert summary.flow_run_id is None and summary.flow_run_url is None
    rows = query(db, "SELECT flow_run_id, flow_run_url FROM runs").to_pylist()
    assert rows == [{"flow_run_id": None, "flow_run_url": None}]
