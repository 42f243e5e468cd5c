"""The ``*_mm`` views compare clips stored in different units: the thesis's clip is in cm."""

import numpy as np
import pytest

from handdb.build import BuildOptions
from handdb.store.query import connect, derived_views
from tests.support.building import build_demo_clips

#: The thesis's Maya clip (centimetres) and a synthetic demo clip (millimetres).
CLIPS = ("thesis-clench", "rapid-s01")


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    return build_demo_clips(tmp_path_factory.mktemp("units"), CLIPS,
                            BuildOptions(export_usd=False))


def test_the_clips_are_stored_in_different_units(db):
    with connect(db) as con:
        units = dict(con.sql("SELECT clip_id, units FROM clips").fetchall())
    assert units == {"thesis-clench": "cm", "rapid-s01": "mm"}


@pytest.mark.parametrize("table, columns", [
    ("joints_3d", ["x", "y", "z", "length_inconsistency"]),
    ("truth_3d", ["x", "y", "z"]),
    ("validation_joint", ["dz_min", "dz_max", "dz_mean", "dz_std", "mpjpe"]),
])
def test_mm_views_scale_each_clip_by_its_own_unit(db, table, columns):
    with connect(db) as con:
        for clip_id, mm_per_unit in [("thesis-clench", 10.0), ("rapid-s01", 1.0)]:
            order = "ORDER BY ALL"
            raw = con.sql(f"SELECT {', '.join(columns)} FROM {table} "
                          f"WHERE clip_id = '{clip_id}' {order}").fetchnumpy()
            mm = con.sql(f"SELECT {', '.join(columns)} FROM {table}_mm "
                         f"WHERE clip_id = '{clip_id}' {order}").fetchnumpy()
            assert len(mm[columns[0]]) == len(raw[columns[0]]) > 0
            for column in columns:
                np.testing.assert_allclose(np.asarray(mm[column], float),
                                           np.asarray(raw[column], float) * mm_per_unit,
                                           equal_nan=True, err_msg=f"{table}.{column}")


def test_the_readme_query_averages_depth_errors_in_mm(db):
    """The README's example: one average depth error per method, every clip in mm."""
    with connect(db) as con:
        mixed = dict(con.sql("SELECT method, avg(dz_mean) FROM validation_joint "
                             "GROUP BY method").fetchall())
        in_mm = dict(con.sql("SELECT method, avg(dz_mean) FROM validation_joint_mm "
                             "GROUP BY method").fetchall())
        per_clip = con.sql("SELECT method, clip_id, avg(dz_mean) * mm_per_unit(any_value(units)),"
                           " count(*) FROM validation_joint GROUP BY ALL").fetchall()
        [(units,)] = con.sql("SELECT DISTINCT units FROM validation_joint_mm").fetchall()
    assert units == "mm"
    for method, expected in in_mm.items():
        rows = [(mean, n) for m, _, mean, n in per_clip if m == method]
        assert expected == pytest.approx(sum(mean * n for mean, n in rows)
                                         / sum(n for _, n in rows))
    thesis_methods = {m for m, clip, _, _ in per_clip if clip == "thesis-clench"}
    assert any(in_mm[m] != pytest.approx(mixed[m]) for m in thesis_methods)


def test_every_mm_view_says_its_columns_are_in_mm(db):
    names = [name for name in derived_views() if name.endswith("_mm")]
    assert {"joints_3d_mm", "truth_3d_mm", "markers_3d_mm", "validation_joint_mm",
            "bone_lengths_mm"} <= set(names)
    with connect(db) as con:
        docs = dict(con.sql("SELECT column_name, comment FROM duckdb_columns() "
                            "WHERE table_name = 'joints_3d_mm'").fetchall())
    assert "mm" in docs["x"] and "clip units" not in docs["x"]
    assert docs["scale"].endswith("pixels per mm")
