"""The benchmark's own machinery: synthetic inboxes, the I/O floor, the growth fit."""

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
