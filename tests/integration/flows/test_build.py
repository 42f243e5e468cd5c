"""The build flow end to end on real files: Prefect, Parquet and DuckDB, no mocks."""

import hashlib

import pytest
from handdb_flows.settings import quick_flows

from handdb.store.database import Store
from handdb.store.query import query
from tests.support.building import run


def build(inbox, db):
    with quick_flows():
        return run(str(inbox), str(db), export_usd=False, workers=2)


def digests(db, exclude=("runs",)):
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*.parquet")) if path.parent.name not in exclude
    }


def test_build_ingests_every_clip_into_every_table(inbox, tmp_path, n_frames):
    db = tmp_path / "db"
    summary = build(inbox, db)
    assert summary.ok and sorted(summary.processed) == ["alpha", "bravo", "charlie"]
    counts = query(str(db), """
        SELECT (SELECT count(*) FROM clips) AS clips,
               (SELECT count(*) FROM joints_3d) AS joints,
               (SELECT count(*) FROM truth_3d) AS truth,
               (SELECT count(*) FROM runs) AS runs,
               (SELECT count(*) FROM quarantine) AS refused""").to_pylist()[0]
    assert counts == {"clips": 3, "joints": 3 * n_frames * 21, "truth": 3 * n_frames * 21,
                      "runs": 1, "refused": 0}
    per_clip = query(str(db), "SELECT clip_id, count(DISTINCT frame) AS frames, "
                              "count(DISTINCT joint) AS joints FROM joints_3d GROUP BY 1")
    assert set(per_clip.column("frames").to_pylist()) == {n_frames}
    assert set(per_clip.column("joints").to_pylist()) == {21}


def test_second_build_changes_nothing(inbox, tmp_path):
    db = tmp_path / "db"
    build(inbox, db)
    before = digests(db)
    summary = build(inbox, db)
    assert summary.processed == [] and sorted(summary.unchanged) == ["alpha", "bravo", "charlie"]
    assert digests(db) == before
    assert query(str(db), "SELECT count(*) AS n FROM runs").column("n")[0].as_py() == 2


def test_changed_file_replaces_only_its_clip(inbox, tmp_path):
    db = tmp_path / "db"
    build(inbox, db)
    before = digests(db)
    track = inbox / "bravo.tracks.csv"
    lines = track.read_text().splitlines()
    frame, joint, u, v, conf = lines[1].split(",")
    lines[1] = ",".join([frame, joint, str(float(u) + 7.0), v, conf])
    track.write_text("\n".join(lines) + "\n")
    summary = build(inbox, db)
    assert summary.processed == ["bravo"]
    after = digests(db)
    changed = {path for path in after if after[path] != before.get(path)}
    assert changed and all("bravo" in path for path in changed)
    moved = query(str(db), f"SELECT u FROM tracks_2d WHERE clip_id = 'bravo' AND frame = {frame} "
                           f"AND joint = '{joint}'").column("u")[0].as_py()
    assert moved == pytest.approx(float(u) + 7.0)


def test_bad_input_is_quarantined_and_the_rest_goes_on(inbox, tmp_path, write_clip):
    db = tmp_path / "db"
    build(inbox, db)
    before = digests(db)
    # a clip that was good turns bad: its stored rows must stay as they were
    track = inbox / "alpha.tracks.csv"
    lines = track.read_text().splitlines()
    lines[5] = lines[5].split(",")[0] + "," + lines[5].split(",")[1] + ",abc,1.0,0.9"
    track.write_text("\n".join(lines) + "\n")
    # a new bad clip and a track file without a sidecar
    write_clip(inbox, "delta", seed=7)
    (inbox / "delta.clip.json").write_text('{"skeleton": "mediapipe21", "hand": "up"}')
    write_clip(inbox, "orphan", seed=8, truth=False)
    (inbox / "orphan.clip.json").unlink()
    write_clip(inbox, "echo", seed=9)
    summary = build(inbox, db)
    assert summary.ok and summary.processed == ["echo"]
    refused = query(str(db), "SELECT file, line, field, reason FROM quarantine ORDER BY file")
    rows = {r["file"]: r for r in refused.to_pylist()}
    assert rows["alpha.tracks.csv"]["line"] == 6 and rows["alpha.tracks.csv"]["field"] == "u"
    assert rows["delta.clip.json"]["field"] in {"hand", "fps"}
    assert "sidecar" in rows["orphan.tracks.csv"]["reason"]
    after = digests(db, exclude=("runs", "quarantine"))
    assert {k: v for k, v in after.items() if "echo" not in k} == \
        {k: v for k, v in before.items() if "quarantine" not in k}


def test_a_build_holds_the_lock(inbox, tmp_path):
    from handdb.errors import DatabaseLockedError

    db = tmp_path / "db"
    with Store(str(db)).lock(), pytest.raises(DatabaseLockedError, match="being built"):
        build(inbox, db)


def _held(db) -> bool:
    """Whether some build holds the database lock (this process's own included)."""
    from handdb.errors import DatabaseLockedError

    try:
        with Store(str(db)).lock():
            return False
    except DatabaseLockedError:
        return True


def test_the_lock_is_held_from_the_plan_to_the_end_of_the_flow(inbox, tmp_path,
                                                               monkeypatch):
    # a second build that started between the first's plan and its flow used to be
    # refused inside its own flow run, with an ERROR log from Prefect
    from handdb_flows.orchestrator import PrefectOrchestrator

    import handdb.build.entry

    db = tmp_path / "db"
    seen = []
    plan, orchestrated = handdb.build.entry.plan_build, PrefectOrchestrator.build

    def planning(*args, **kwargs):
        seen.append(("plan", _held(db)))
        return plan(*args, **kwargs)

    def orchestrating(self, *args, **kwargs):
        seen.append(("orchestrator", _held(db), kwargs["locked"]))
        return orchestrated(self, *args, **kwargs)

    # run_build (handdb.build.entry) plans with the plan_build it imported
    monkeypatch.setattr(handdb.build.entry, "plan_build", planning)
    monkeypatch.setattr(PrefectOrchestrator, "build", orchestrating)
    summary = build(inbox, db)
    assert summary.ok and len(summary.processed) == 3
    assert seen == [("plan", True), ("orchestrator", True, True)]
    assert not _held(db)


def test_the_prefect_runner_refuses_a_locked_database_before_its_flow(inbox, tmp_path,
                                                                     caplog):
    from handdb_flows.orchestrator import PrefectOrchestrator

    from handdb.build import BuildOptions
    from handdb.errors import DatabaseLockedError

    db = tmp_path / "db"
    with Store(str(db)).lock(), pytest.raises(DatabaseLockedError, match="being built by"):
        PrefectOrchestrator().build(str(inbox), str(db), BuildOptions(export_usd=False),
                                    runner="thread", workers=1)
    assert not [r for r in caplog.records if r.levelname in ("ERROR", "CRITICAL")]
    assert not [r for r in caplog.records if r.name.startswith("prefect.flow_runs")]


@pytest.mark.slow
def test_further_methods_are_validated_on_request(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "solo", seed=4)
    with quick_flows():
        summary = run(str(inbox), str(tmp_path / "db"), export_usd=False, workers=1,
                      compare=("model-fit",))
    assert summary.ok
    methods = query(str(tmp_path / "db"), "SELECT DISTINCT method FROM validation_joint "
                                          "ORDER BY method").column(0).to_pylist()
    assert methods == ["kinematic", "model-fit", "thesis", "thesis-nocheck"]
