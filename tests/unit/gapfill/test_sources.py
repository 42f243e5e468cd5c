import numpy as np
import pytest

from handdb.gapfill.evaluate import (
    RANDOM_MASK,
    THESIS_MASK,
    evaluate_clip,
    overall_rmse,
    pooled_rmse,
)
from handdb.gapfill.sources import (
    DatabaseSource,
    SyntheticSource,
    chart_path,
    database_sources,
    store_evaluation,
)
from handdb.ingest import discover, load_clip
from handdb.store.database import Store

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_only_the_database_clip_with_complete_tracks_is_a_source(demo_db):
    assert [s.clip_id for s in database_sources(demo_db)] == ["rapid-s01"]
    assert DatabaseSource(demo_db, "wave-s02").load() is None
    assert DatabaseSource(demo_db, "no-such-clip").load() is None


def test_a_database_clip_loads_as_its_inbox_files_read(demo_db, tmp_path):
    from handdb.demo import write_demo_inbox

    write_demo_inbox(tmp_path)
    entry = next(e for e in discover(tmp_path).clips if e.clip_id == "rapid-s01")
    expected = load_clip(entry)
    clip = DatabaseSource(demo_db, "rapid-s01").load()
    assert clip.skeleton.name == expected.skeleton.name
    np.testing.assert_allclose(clip.uv, expected.uv, rtol=0, atol=1e-9)
    np.testing.assert_allclose(clip.truth, expected.truth, rtol=0, atol=1e-9)


def test_evaluation_lands_in_the_database_partition_and_report(tmp_path):
    source = SyntheticSource("rapid", 100, seed=0)
    clip = source.load()
    assert clip.clip_id == "synthetic-rapid-seed0"
    methods = ["previous", "auto"]
    evaluation = evaluate_clip(clip.clip_id, clip.uv, clip.skeleton,
                               masks=[THESIS_MASK, RANDOM_MASK], methods=methods)
    store = Store(str(tmp_path / "db"))
    chart = store_evaluation(store, clip, evaluation, methods)
    assert chart == chart_path(store, clip.clip_id)
    assert chart.endswith("reports/synthetic-rapid-seed0/gapfill.png")
    with open(chart, "rb") as fh:
        assert fh.read(8) == PNG_SIGNATURE
    rows = store.read("gapfill_eval", clip.clip_id)
    assert rows.equals(evaluation.table)
    pooled, direct = pooled_rmse(rows), overall_rmse(evaluation)
    assert pooled.keys() == direct.keys()
    for key in direct:
        assert pooled[key] == pytest.approx(direct[key], rel=1e-12)
    assert pooled[(RANDOM_MASK, "auto")] < pooled[(RANDOM_MASK, "previous")]
