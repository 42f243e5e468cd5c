"""The build's plan: stage keys decide which clips, and which of their stages, run again."""

import hashlib
import shutil
import subprocess
import sys
from dataclasses import replace
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

from handdb import gapfill, lifting
from handdb.build import BuildOptions, build_in_process, plan_build, stages
from handdb.build.keys import STAGES, stage_keys
from handdb.ingest import discover
from handdb.ingest.limits import MAX_FILE_BYTES
from handdb.store.database import Store
from handdb.store.query import query


def digests(db: Path) -> dict[str, str]:
    return {p.relative_to(db).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(db.rglob("*")) if p.is_file() and p.parent.name != "runs"
            and p.name != ".lock"}


@pytest.fixture
def built(inbox, tmp_path):
    db = str(tmp_path / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["alpha", "bravo", "charlie"]
    return inbox, db


def test_keys_chain_through_the_stages():
    base = stage_keys("h", BuildOptions(), "r", marker_clip=False)
    assert list(base) == list(STAGES)
    other_fill = stage_keys("h", BuildOptions(gap_fill="linear"), "r", marker_clip=False)
    changed = [s for s in STAGES if base[s] != other_fill[s]]
    assert changed == ["gap_fill", "lift", "validate", "export"]
    other_ratios = stage_keys("h", BuildOptions(), "r2", marker_clip=False)
    assert [s for s in STAGES if base[s] != other_ratios[s]] == [
        "lengths", "lift", "validate", "export"]
    marker = stage_keys("h", BuildOptions(), "r", marker_clip=True)
    assert marker["lengths"] == marker["gap_fill"] == marker["lift"]


def test_a_built_database_has_nothing_to_do(built):
    inbox, db = built
    plan = plan_build(inbox, db, BuildOptions(export_usd=False))
    assert plan.nothing_to_do and len(plan.unchanged) == 3


def test_a_new_gap_filling_version_redoes_gap_filling_and_what_follows(built, monkeypatch):
    inbox, db = built
    before = digests(Path(db))
    monkeypatch.setattr(gapfill, "VERSION", gapfill.VERSION + 1)
    plan = plan_build(inbox, db, BuildOptions(export_usd=False))
    assert {c.clip_id: c.start for c in plan.clips} == dict.fromkeys(
        ["alpha", "bravo", "charlie"], "gap_fill")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False), plan=plan)
    assert sorted(summary.processed) == ["alpha", "bravo", "charlie"]
    after = digests(Path(db))
    # the algorithm did not change: every table is what it was, only the keys moved (in the
    # clips rows, and in the record of files, which holds the clips files' checksums)
    keyed = ("clips/", "clip_files/")
    assert {k: v for k, v in after.items() if not k.startswith(keyed)} == \
        {k: v for k, v in before.items() if not k.startswith(keyed)}
    assert plan_build(inbox, db, BuildOptions(export_usd=False)).nothing_to_do


def test_a_resumed_lift_reads_the_earlier_stages_back(built, monkeypatch):
    inbox, db = built
    monkeypatch.setattr(lifting, "VERSION", lifting.VERSION + 1)
    plan = plan_build(inbox, db, BuildOptions(export_usd=False))
    assert {c.start for c in plan.clips} == {"lift"}
    for track in Path(inbox).glob("*.tracks.csv"):
        track.write_text("not read again\n")  # the hash in the plan still matches
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False), plan=plan)
    assert sorted(summary.processed) == ["alpha", "bravo", "charlie"] and not summary.refusals


def test_an_edited_file_redoes_its_clip_from_ingest(built):
    inbox, db = built
    sidecar = Path(inbox) / "bravo.clip.json"
    sidecar.write_text(sidecar.read_text().replace('"fps": 30.0', '"fps": 25.0'))
    plan = plan_build(inbox, db, BuildOptions(export_usd=False))
    assert {c.clip_id: c.start for c in plan.todo} == {"bravo": "ingest"}


def thread_build_in_a_fresh_process(inbox: Path, db: str) -> tuple[dict, bool]:
    """Build with the Prefect thread runner in a new interpreter (USD export off).

    Returns the summary's clip counts and whether Prefect was imported.
    """
    code = ("import sys; from handdb.build import BuildOptions, run_build; "
            "s = run_build(sys.argv[1], sys.argv[2], BuildOptions(export_usd=False), "
            "runner='thread'); "
            "print(s.n_clips, len(s.unchanged), len(s.processed), 'prefect' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(inbox), db], capture_output=True,
                         text=True, check=True).stdout.split()
    counts = dict(zip(("clips", "unchanged", "processed"), map(int, out[:3]), strict=True))
    return counts, out[3] == "True"


def test_nothing_to_do_never_starts_prefect(built):
    inbox, db = built
    counts, prefect = thread_build_in_a_fresh_process(inbox, db)
    assert counts["unchanged"] == 3 and not prefect


def test_an_empty_inbox_builds_without_prefect_and_stores_the_xray_tables(tmp_path):
    inbox, db = tmp_path / "inbox", str(tmp_path / "db")
    inbox.mkdir()
    shutil.copyfile(str(files("handdb") / "data" / "chaudhry_table1.xray.csv"),
                    inbox / "chaudhry_table1.xray.csv")
    counts, prefect = thread_build_in_a_fresh_process(inbox, db)
    assert counts["clips"] == 0 and not prefect
    assert query(db, "SELECT count(*) AS n FROM xray_measurements").column("n")[0].as_py() > 0
    assert query(db, "SELECT count(*) AS n FROM runs").column("n")[0].as_py() == 1


def test_an_unstorable_xray_name_and_an_oversized_track_are_refused_and_the_rest_builds(
        inbox, tmp_path):
    xray = inbox / ("x" * 240 + ".xray.csv")
    shutil.copyfile(str(files("handdb") / "data" / "chaudhry_table1.xray.csv"), xray)
    big = inbox / "bravo.tracks.csv"
    with big.open("r+b") as track:
        track.truncate(MAX_FILE_BYTES + 1)
    db = str(tmp_path / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["alpha", "charlie"]
    refused = {Path(r.file).name: r for r in summary.refusals}
    assert refused[xray.name].field == "file name"
    assert "at most 128 bytes" in refused[xray.name].reason
    assert "handdb reads such files up to" in refused[big.name].reason
    stored = query(db, "SELECT file FROM quarantine").column("file").to_pylist()
    assert {Path(f).name for f in stored} >= {xray.name, big.name}


def test_a_clip_whose_joints_cannot_all_be_placed_is_flagged_and_keys_the_rest(
        inbox, tmp_path):
    options = BuildOptions()
    [entry] = [e for e in discover(inbox).clips if e.clip_id == "alpha"]
    result = stages.lift_clip(stages.fill(stages.resolve_bone_lengths(
        stages.ClipResult(clip=stages.ingest(entry)), None), options), options)
    result = stages.validate(result, options)
    xyz = result.lifted.xyz.copy()
    xyz[10:15, 3] = np.nan
    unplaced = replace(result, lifted=replace(result.lifted, xyz=xyz))
    exported = stages.export(unplaced, Store(str(tmp_path / "db")), options)
    assert exported.usd_path == "usd/alpha.usd"
    [reason] = [r for r in exported.verdict.reasons if r.startswith("USD animates")]
    assert f"frames 0-{len(xyz) - 1}: 5 joint positions in 5 frames (from frame 10)" in reason
    assert exported.verdict.rows[10:15, 3].all() and exported.verdict.flagged
    xyz[:] = np.nan
    nowhere = stages.export(replace(result, lifted=replace(result.lifted, xyz=xyz)),
                            Store(str(tmp_path / "db2")), options)
    assert nowhere.usd_path is None
    assert any(r.startswith("no USD or preview written") for r in nowhere.verdict.reasons)
    assert not list((tmp_path / "db2").rglob("*.usd"))
