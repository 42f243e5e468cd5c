"""Arrow schemas of the database tables, read from ``schemas/tables/*.json``.

Each table's contract is a JSON file: its fields (name, Arrow type, nullability, doc),
how it is partitioned on disk (``clip``: one file per clip; ``global``: one file;
``source``: one file per input file; ``run``: one file per run) and its sort order.
Code builds tables with :func:`from_columns` or checks them with :func:`conform`, so what is
written always matches the contract.
"""

from __future__ import annotations

import json
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
import numpy.typing as npt
import pyarrow as pa
import pyarrow.compute as pc

from handdb.errors import SchemaError
from handdb.paths import SCHEMAS_DIR

TABLES_DIR = SCHEMAS_DIR / "tables"

#: Tables :func:`conform` returned, by table name and identity: conformed again (the store
#: conforms what it commits, often tables :func:`from_columns` built) one is returned as
#: it is, without a second check. Arrow tables are immutable, and an entry leaves with its
#: table, so an identity never stands for another table.
_CONFORMED: weakref.WeakValueDictionary[tuple[str, int], pa.Table] = (
    weakref.WeakValueDictionary())

_SCALAR_TYPES: dict[str, pa.DataType] = {
    "string": pa.string(),
    "bool": pa.bool_(),
    "int16": pa.int16(),
    "int32": pa.int32(),
    "int64": pa.int64(),
    "float32": pa.float32(),
    "float64": pa.float64(),
    "timestamp[us, UTC]": pa.timestamp("us", tz="UTC"),
}


def _arrow_type(name: str) -> pa.DataType:
    if name.startswith("list<") and name.endswith(">"):
        return pa.list_(_arrow_type(name[5:-1]))
    try:
        return _SCALAR_TYPES[name]
    except KeyError:
        raise SchemaError(f"unknown type '{name}' in {TABLES_DIR}") from None


@dataclass(frozen=True)
class TableSpec:
    """A table's contract: schema, on-disk partitioning and sort order."""

    name: str
    schema: pa.Schema
    partition: str
    sort_by: tuple[str, ...]
    description: str


def table_names() -> tuple[str, ...]:
    """Names of every table with a contract in ``schemas/tables``."""
    return tuple(sorted(p.stem for p in TABLES_DIR.glob("*.json")))


@cache
def table_spec(name: str) -> TableSpec:
    """Return the contract of table ``name``."""
    path = TABLES_DIR / f"{name}.json"
    if not path.is_file():
        raise SchemaError(f"no table '{name}'; tables: {', '.join(table_names())}")
    doc = json.loads(path.read_text())
    fields = [
        pa.field(f["name"], _arrow_type(f["type"]), nullable=f["nullable"],
                 metadata={"doc": f.get("doc", "")})
        for f in doc["fields"]
    ]
    return TableSpec(
        name=name,
        schema=pa.schema(fields, metadata={"table": name, "description": doc["description"]}),
        partition=doc["partition"],
        sort_by=tuple(doc["sort_by"]),
        description=doc["description"],
    )


def schema(name: str) -> pa.Schema:
    """Arrow schema of table ``name``."""
    return table_spec(name).schema


def empty(name: str) -> pa.Table:
    """An empty table with the schema of ``name``."""
    return schema(name).empty_table()


def conform(name: str, table: pa.Table) -> pa.Table:
    """Check ``table`` against the contract of ``name`` and return it in contract form.

    Columns are put in contract order and cast to the contract types where the cast is
    safe; the rows are sorted by the contract's sort order so that equal inputs give
    byte-identical files.

    Raises
    ------
    SchemaError
        On a missing or extra column, an unsafe cast, or a null in a non-nullable column.
    """
    if _CONFORMED.get((name, id(table))) is table:
        return table
    target = schema(name)
    # `column_names` and `names` build a new list on every access: take each once
    given, wanted = table.column_names, set(target.names)
    present = set(given)
    missing = [column for column in target.names if column not in present]
    extra = [column for column in given if column not in wanted]
    if missing or extra:
        raise SchemaError(
            f"table '{name}': missing columns {missing}, unexpected columns {extra}"
        )
    columns = []
    for fld in target:
        column = table.column(fld.name)
        if not fld.nullable and column.null_count:
            raise SchemaError(f"table '{name}': column '{fld.name}' has "
                              f"{column.null_count} nulls but is not nullable")
        try:
            columns.append(_cast(column, fld.type))
        except (pa.ArrowInvalid, pa.ArrowNotImplementedError) as exc:
            raise SchemaError(f"table '{name}': column '{fld.name}' cannot be "
                              f"{fld.type}: {exc}") from None
    result = pa.Table.from_arrays(columns, schema=target)
    sort_by = table_spec(name).sort_by
    if not is_sorted(result, sort_by):
        result = result.sort_by([(k, "ascending") for k in sort_by])
    _CONFORMED[(name, id(result))] = result
    return result


def is_sorted(table: pa.Table, keys: tuple[str, ...]) -> bool:
    """Whether the rows are already in ascending order of ``keys`` (compared in turn).

    A check in linear time that spares :func:`conform` a sort of tables built in order
    (the pipeline's per-clip tables are) and of tables conformed twice. A key column with
    nulls or NaN counts as unsorted, so the sort decides where those go.
    """
    n_rows = table.num_rows
    if n_rows < 2:
        return True
    in_order = None
    for key in reversed(keys):
        column = table.column(key)
        if column.null_count:
            return False
        head, tail = column.slice(0, n_rows - 1), column.slice(1)
        ahead, tied = pc.less(head, tail), pc.equal(head, tail)
        in_order = pc.or_(ahead, tied if in_order is None else pc.and_(tied, in_order))
    return bool(pc.all(in_order).as_py())


def labels(names: Sequence[str] | np.ndarray, codes: np.ndarray,
           valid: npt.ArrayLike | None = None) -> pa.Array:
    """The string column ``names[codes]``, null where ``valid`` is ``False``.

    Parameters
    ----------
    names
        The distinct strings (a skeleton's joints, the methods used), a sequence or a
        numpy string array.
    codes
        ``(n,) int``: index into ``names`` of each row.
    valid
        ``(n,) bool``: rows that have a value; all of them when ``None``.

    Returns
    -------
    pyarrow.Array
        ``(n,) string``. Arrow takes the rows from the few names in one call, where a numpy
        string or object array would be converted string by string.
    """
    mask = None if valid is None else ~np.asarray(valid, dtype=bool)
    indices = pa.array(np.asarray(codes, dtype=np.int32), mask=mask)
    return pa.array(list(names), pa.string()).take(indices)


def per_point(rows: pa.Table, columns: Sequence[str], shape: tuple[int, int],
              missing: float | bool = np.nan) -> np.ndarray:
    """Rows of a per-point table (``frame``, ``joint_index``) as a dense array.

    Parameters
    ----------
    rows
        Rows of ``joints_3d``, ``truth_3d``, ``tracks_2d`` or ``markers_3d`` of one clip.
    columns
        The ``C`` columns to gather, e.g. ``("x", "y", "z")``.
    shape
        ``(T, J)``: the clip's frames and its skeleton's joints.
    missing
        Value where the table has no row.

    Returns
    -------
    numpy.ndarray
        ``(T, J, C)``, of the columns' common dtype.
    """
    values = np.stack([rows.column(c).to_numpy(zero_copy_only=False) for c in columns],
                      axis=-1)
    out = np.full((*shape, len(columns)), missing, dtype=values.dtype)
    out[rows.column("frame").to_numpy(), rows.column("joint_index").to_numpy()] = values
    return out


def _cast(values: pa.Array | pa.ChunkedArray, to: pa.DataType) -> pa.Array | pa.ChunkedArray:
    """``values`` as type ``to``, refusing a lossy cast; ``values`` itself when it is ``to``.

    Casting a column to its own type copies nothing but still costs a compute call, about
    10 µs, for each of the 30 to 40 columns of a table.
    """
    return values if values.type == to else values.cast(to, safe=True)


def _column(value: Any, n: int) -> pa.Array:
    """Return ``value`` as an Arrow array; a scalar is repeated ``n`` times.

    NaN in a float array is null (``from_pandas``). The mask of a float array is numpy's
    ``isnan``, which is two to three times quicker than pyarrow's own scan of the values,
    more so on a column that is a strided view (``uv[:, 0]``).
    """
    if isinstance(value, pa.ChunkedArray):
        return value.combine_chunks()
    if isinstance(value, str) or not hasattr(value, "__len__"):
        return pa.repeat(value, n)
    if isinstance(value, np.ndarray) and value.dtype.kind == "f" and value.ndim == 1:
        missing = np.isnan(value)
        return pa.array(value, mask=missing if missing.any() else None)
    return pa.array(value, from_pandas=True)


def from_columns(name: str, columns: dict[str, Any]) -> pa.Table:
    """Build table ``name`` from a mapping of column name to values (arrays or lists).

    Scalars are broadcast to the length of the longest column.
    """
    lengths = [len(v) for v in columns.values() if hasattr(v, "__len__") and not isinstance(v, str)]
    n = max(lengths, default=1)
    arrays = {}
    for fld in schema(name):
        if fld.name not in columns:
            raise SchemaError(f"table '{name}': no values given for column '{fld.name}'")
        try:
            arrays[fld.name] = _cast(_column(columns[fld.name], n), fld.type)
        except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError) as exc:
            raise SchemaError(f"table '{name}': column '{fld.name}' cannot be "
                              f"{fld.type}: {exc}") from None
    extra = sorted(set(columns) - set(schema(name).names))
    if extra:
        raise SchemaError(f"table '{name}': unexpected columns {extra}")
    return conform(name, pa.table(arrays))
