import json

import pyarrow as pa
import pytest

from handdb.errors import SchemaError
from handdb.store import tables


def test_every_contract_loads_with_docs():
    for name in tables.table_names():
        spec = tables.table_spec(name)
        assert spec.partition in {"clip", "global", "source", "run"}
        assert set(spec.sort_by) <= set(spec.schema.names)
        undocumented = [field.name for field in spec.schema if not field.metadata[b"doc"]]
        assert undocumented == [], f"table {name}: columns without a doc: {undocumented}"


def test_contract_files_are_the_source_of_the_schema():
    doc = json.loads((tables.TABLES_DIR / "joints_3d.json").read_text())
    assert tables.schema("joints_3d").names == [f["name"] for f in doc["fields"]]


def test_from_columns_orders_casts_and_sorts():
    table = tables.from_columns("truth_3d", {
        "clip_id": "c", "frame": [1, 0], "joint": ["wrist", "wrist"], "joint_index": [0, 0],
        "x": [1.0, 2.0], "y": [0.0, 0.0], "z": [3, 4],
    })
    assert table.schema == tables.schema("truth_3d")
    assert table.column("frame").to_pylist() == [0, 1]
    assert table.column("x").to_pylist() == [2.0, 1.0]


def test_conform_refuses_missing_extra_and_null_columns():
    good = tables.empty("joint_ratios")
    with pytest.raises(SchemaError, match="missing columns"):
        tables.conform("joint_ratios", good.drop_columns(["mean"]))
    with pytest.raises(SchemaError, match="unexpected columns"):
        tables.conform("joint_ratios", good.append_column("extra", pa.array([], pa.int8())))
    with pytest.raises(SchemaError, match="not nullable"):
        tables.from_columns("truth_3d", {
            "clip_id": "c", "frame": [0], "joint": ["wrist"], "joint_index": [0],
            "x": [None], "y": [0.0], "z": [0.0]})


def test_conform_refuses_unsafe_casts():
    with pytest.raises(SchemaError, match="cannot be"):
        tables.from_columns("truth_3d", {
            "clip_id": "c", "frame": [0.5], "joint": ["wrist"], "joint_index": [0],
            "x": [0.0], "y": [0.0], "z": [0.0]})


@pytest.mark.parametrize("frames, joints, expected", [
    ([0, 0, 1, 1], [0, 1, 0, 1], True),
    ([0, 0, 1, 1], [1, 0, 0, 1], False),
    ([0, 1, 1, 0], [0, 0, 1, 1], False),
    ([0, 0, 0, 0], [0, 0, 0, 0], True),
])
def test_is_sorted_compares_keys_in_turn(frames, joints, expected):
    table = pa.table({"frame": frames, "joint_index": joints})
    assert tables.is_sorted(table, ("frame", "joint_index")) is expected
    in_order = table.sort_by([("frame", "ascending"), ("joint_index", "ascending")])
    assert table.equals(in_order) is expected


def test_is_sorted_leaves_nan_and_null_keys_to_the_sort():
    assert not tables.is_sorted(pa.table({"k": [0.0, float("nan")]}), ("k",))
    assert not tables.is_sorted(pa.table({"k": [0, None]}), ("k",))


def test_from_columns_broadcasts_scalars_and_takes_arrow_arrays():
    table = tables.from_columns("truth_3d", {
        "clip_id": "c", "frame": pa.chunked_array([[0], [1]]), "joint": ["wrist", "wrist"],
        "joint_index": pa.array([0, 0]), "x": 1.5, "y": [0.0, 0.0], "z": [3.0, 4.0],
    })
    assert table.column("clip_id").to_pylist() == ["c", "c"]
    assert table.column("x").to_pylist() == [1.5, 1.5]
    assert table.column("frame").to_pylist() == [0, 1]


def test_a_conformed_table_is_conformed_again_as_it_is():
    columns = {"clip_id": "c", "frame": [1, 0], "joint": ["wrist", "wrist"],
               "joint_index": [0, 0], "x": [1.0, 2.0], "y": [0.0, 0.0], "z": [3, 4]}
    table = tables.from_columns("truth_3d", columns)
    assert tables.conform("truth_3d", table) is table
    with pytest.raises(SchemaError, match="missing columns"):
        tables.conform("joint_ratios", table)       # remembered per table name
    unsorted = pa.table({**{k: table.column(k) for k in table.column_names},
                         "frame": pa.array([1, 0], pa.int64())})
    again = tables.conform("truth_3d", unsorted.select(table.column_names))
    assert again.column("frame").to_pylist() == [0, 1]    # an equal-looking table is checked
