"""DuckDB over the database: one view per table, named like the table.

Each table's view scans an Arrow dataset of the table's Parquet files, listed when the
connection is made (a folder listing, never a glob: a database path may hold pattern
characters); the files are read in place, lazily, in the table's contract schema. A table
with no file yet is an empty view with the contract's columns, so every query that names a
table works on any database. Derived views in ``schemas/views/*.sql`` are created after the
table views.
"""

from __future__ import annotations

import duckdb
import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.fs as pafs

from handdb.paths import SCHEMAS_DIR
from handdb.store import tables
from handdb.store.database import Store

VIEWS_DIR = SCHEMAS_DIR / "views"


def arrow_filesystem(store: Store) -> pafs.FileSystem:
    """The store's filesystem as Arrow reads it."""
    if store.is_local:
        return pafs.LocalFileSystem()
    return pafs.PyFileSystem(pafs.FSSpecHandler(store.fs))


def table_rows(store: Store, table: str) -> ds.Dataset | pa.Table:
    """The committed rows of ``table``: a dataset over its files, or an empty table."""
    files = store.table_files(table)
    if not files:
        return tables.empty(table)
    return ds.dataset(files, schema=tables.schema(table), format="parquet",
                      filesystem=arrow_filesystem(store))


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
    for name in tables.table_names():
        con.register(f"_rows_{name}", table_rows(store, name))
        con.execute(f"CREATE OR REPLACE VIEW {name} AS SELECT * FROM _rows_{name}")
    for sql in sorted(VIEWS_DIR.glob("*.sql")):
        con.execute(sql.read_text())
    return con


def query(db: str | Store, sql: str) -> pa.Table:
    """Run ``sql`` against the database at ``db`` and return the result as Arrow.

    Raises
    ------
    DatabasePathError
        When there is no database at ``db``.
    """
    store = db if isinstance(db, Store) else Store(str(db))
    store.check_readable()
    with connect(store) as con:
        return con.sql(sql).to_arrow_table()
