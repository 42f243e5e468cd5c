"""A float column built with numpy's NaN mask is pyarrow's ``from_pandas`` column, and
writes the same Parquet bytes."""

import io

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from handdb.store.tables import _column


def _parquet(array: pa.Array) -> bytes:
    sink = io.BytesIO()
    pq.write_table(pa.table({"value": array}), sink, compression="zstd")
    return sink.getvalue()


@pytest.mark.parametrize("case", ["nan", "none", "all", "strided", "float32", "empty"])
def test_float_column_is_from_pandas(case):
    rng = np.random.default_rng(4)
    points = rng.normal(size=(500, 3))
    points[rng.random(points.shape) < 0.2] = np.nan
    values = {"nan": points[:, 0].copy(), "none": np.arange(500.0),
              "all": np.full(500, np.nan), "strided": points[:, 1],
              "float32": points[:, 2].astype(np.float32), "empty": np.empty(0)}[case]
    got = _column(values, values.size)
    expected = pa.array(values, from_pandas=True)
    assert got.type == expected.type
    assert got.null_count == expected.null_count
    assert got.equals(expected)
    assert _parquet(got) == _parquet(expected)
