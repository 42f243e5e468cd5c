import json

import pyarrow as pa
import pytest

from handdb import tables
from handdb.errors import SchemaError


def test_every_contract_loads_with_docs():
    for name in tables.table_names():
        spec = tables.table_spec(name)
        assert spec.partition in {"clip", "global", "source", "run"}
        assert set(spec.sort_by) <= set(spec.schema.names)
        for field in spec.schema:
            assert field.metadata[b"doc"] is not None


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
