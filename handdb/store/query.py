"""DuckDB over the database: one view per table, named like the table.

Views read the Parquet files in place (``read_parquet`` over ``<db>/<table>/*.parquet``);
a table with no file yet is an empty view with the contract's columns, so every query
that names a table works on any database. Derived views in ``schemas/views/*.sql`` are
created after the table views.
"""

from __future__ import annotations

import duckdb
import pyarrow as pa

from handdb.paths import SCHEMAS_DIR
from handdb.store import tables
from handdb.store.database import PARQUET_SUFFIX, Store

VIEWS_DIR = SCHEMAS_DIR / "views"


def _quote(text: str) -> str:
    return "'" + text.replace("'", "''") + "'"


def connect(db: str | Store, *, database: str = ":memory:") -> duckdb.DuckDBPyConnection:
    """Open a DuckDB connection with a view for every table of the database at ``db``.

    Parameters
    ----------
    db
        Database folder or fsspec URL, or a :class:`~handdb.store.database.Store`.
    database
        DuckDB's own database (in memory by default: the data stays in Parquet).
    """
    store = db if isinstance(db, Store) else Store(str(db))
    con = duckdb.connect(database)
    if not store.is_local:
        con.register_filesystem(store.fs)
    for name in tables.table_names():
        if store.table_files(name):
            pattern = store.uri(name, f"*{PARQUET_SUFFIX}")
            con.execute(
                f"CREATE OR REPLACE VIEW {name} AS SELECT * FROM "
                f"read_parquet({_quote(pattern)}, union_by_name = true)"
            )
        else:
            con.register(f"_empty_{name}", tables.empty(name))
            con.execute(f"CREATE OR REPLACE VIEW {name} AS SELECT * FROM _empty_{name}")
    for sql in sorted(VIEWS_DIR.glob("*.sql")):
        con.execute(sql.read_text())
    return con


def query(db: str | Store, sql: str) -> pa.Table:
    """Run ``sql`` against the database at ``db`` and return the result as Arrow."""
    with connect(db) as con:
        return con.sql(sql).to_arrow_table()
