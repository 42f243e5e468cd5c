"""The benchmark's own machinery: synthetic inboxes, the I/O floor, the growth fit."""

import json
import time

import numpy as np
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq
import pytest

from handdb.build import stages as pipeline
from handdb.ingest import discover
from handdb.store.database import Store
from tests.support.benchmarks import benchmark_module


@pytest.fixture(scope="module")
def bench():
    """``benchmarks/run.py`` as a module."""
    with benchmark_module("run") as module:
        yield module


def test_fitted_exponent_recovers_power_laws(bench):
    sizes = [10.0, 100.0, 1000.0]
    assert bench.fitted_exponent(sizes, [2 * s for s in sizes]) == pytest.approx(1.0)
    assert bench.fitted_exponent(sizes, [s ** 0.5 for s in sizes]) == pytest.approx(0.5)


def test_inbox_clips_load_and_repeat_the_pool(bench, tmp_path, monkeypatch):
    monkeypatch.setattr(bench, "POOL_SIZE", 2)
    inbox = tmp_path / "inbox"
    assert bench.write_inbox(inbox, 3, 60) == 180
    entries = discover(inbox).clips
    assert [e.clip_id for e in entries] == ["c0000", "c0001", "c0002"]
    clips = [pipeline.ingest(e) for e in entries]
    assert all(c.n_frames == 60 and c.truth is not None for c in clips)
    assert not clips[0].observed.all()
    np.testing.assert_array_equal(clips[2].uv, clips[0].uv)
    assert not np.array_equal(clips[1].uv, clips[0].uv, equal_nan=True)


def test_io_floor_writes_every_csv_row_as_parquet(bench, tmp_path):
    inbox = tmp_path / "inbox"
    bench.write_inbox(inbox, 1, 30)
    timing = bench.io_floor(inbox, tmp_path / "floor")
    assert timing.wall > 0
    for path in inbox.glob("*.csv"):
        written = pq.read_table(tmp_path / "floor" / f"{path.name}.parquet")
        assert written.equals(pa_csv.read_csv(path))


def test_stage_timings_commit_every_clip(bench, tmp_path):
    inbox, db = tmp_path / "inbox", tmp_path / "db"
    bench.write_inbox(inbox, 2, 40)
    timings = bench.stage_timings(inbox, db)
    assert list(timings) == list(bench.STAGES)
    assert all(t.frames == 80 for t in timings.values())
    assert sorted(Store(str(db)).clip_build_keys()) == ["c0000", "c0001"]


def test_query_database_answers_every_query(bench, tmp_path, monkeypatch):
    monkeypatch.setattr(bench, "QUERY_CLIPS", 2)
    n_rows = bench.write_query_database(tmp_path / "db", 2 * 21 * 50)
    assert n_rows == 2 * 21 * 50
    assert set(bench.query_latencies(tmp_path / "db")) == set(bench.QUERIES)


def build_figures(n_clips, n_frames, cpu, wall, rss):
    """A row of ``run_builds`` as the targets read it."""
    return {"n_clips": n_clips, "n_frames": n_frames, "frames": n_clips * n_frames,
            "cpu_seconds": cpu, "maxrss_mb": rss, "floor_ratio_cpu": wall / 2,
            "floor_ratio": wall, "load": 1.0}


def test_targets_read_the_figures_of_one_run(bench):
    results = {
        "startup": {"wall_seconds": 4.0, "load": 1.0},
        "noop": {"wall_seconds": 2.5, "n_clips": 40, "n_frames": 5000, "load": 1.0},
        "commands": {"help": 0.4, "sql": 1.2, "load": 1.0},
        # 0.1 s CPU per 300-frame clip, of which 300 frames at 0.2 ms: 40 ms fixed
        "by_clips": [build_figures(10, 300, 1.0, 9.0, 500.0),
                     build_figures(100, 300, 10.0, 9.0, 600.0)],
        "by_frames": [build_figures(4, 1000, 0.8, 9.0, 500.0),
                      build_figures(4, 20_000, 16.0, 5.0, 700.0)],
    }
    rows = bench.targets(results)
    assert [(r.figure.split(",")[0], r.met) for r in rows] == [
        ("empty build", True), ("rebuild with nothing to do", False),
        ("handdb --help", True), ('handdb sql "SELECT 1"', False),
        ("marginal build / I/O floor", True), ("marginal build / I/O floor", False),
        ("fixed cost per clip", True), ("peak RSS", True)]
    assert rows[6].value == pytest.approx(40.0)
    assert rows[7].value == pytest.approx(1.2)


def build_here(inbox, db, runner):
    """``bench.build`` in this process: the figures a fresh process would print.

    A fresh process per build costs seconds of imports each, too slow for a smoke test;
    resource usage is this process's, so only the shape of the figures is checked.
    """
    from handdb.build import run_build

    start = time.perf_counter()
    summary = run_build(str(inbox), str(db), runner=runner)
    seconds = time.perf_counter() - start
    return {"import_seconds": 0.0, "flow_seconds": seconds, "process_seconds": seconds,
            "cpu_seconds": seconds, "maxrss_mb": 100.0, "processed": len(summary.processed),
            "failed": len(summary.failed), "refused": len(summary.refusals),
            "wall_seconds": seconds, "load": 1.0}


def test_the_quick_run_prints_every_target(bench, tmp_path, capsys, monkeypatch):
    """The whole benchmark at smoke-test sizes, builds in this process on the local runner."""
    monkeypatch.setattr(bench, "OUT_DIR", tmp_path / "out")
    monkeypatch.setattr(bench, "PREFECT_HOME", tmp_path / "out" / "prefect-home")
    monkeypatch.setattr(bench, "QUERY_CLIPS", 4)
    monkeypatch.setattr(bench, "build", build_here)
    results = bench.main(bench.QUICK, tmp_path / "bench.json", runner="local")
    printed = capsys.readouterr().out
    table = printed.split("issue 16's targets")[1]
    assert table.count("\n| ") == 1 + 8
    for row in results["targets"]:
        assert f"| {row['figure']} | {row['shown']} |" in table
    assert all(r["processed"] == r["n_clips"] for r in results["by_clips"])
    assert results["noop"]["processed"] == 0


def test_prefect_overhead_runs_one_task_per_clip_as_the_build(bench, capsys):
    """The Prefect-alone figure comes from a real flow whose one task per clip completed."""
    bench.child_prefect_overhead(5)
    figures = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert figures["tasks"] == 5
    assert figures["seconds"] > 0
