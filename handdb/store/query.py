"""DuckDB over the database: one view per table, named like the table.

Each table's view scans the table's Parquet files (how: see the last paragraph), listed when
the connection is made (a folder listing, never a glob: a database path may hold pattern
characters); the files are read in place when a statement scans the view, in the
table's contract schema. A table with no file yet is an empty view with the contract's
columns, so every query that names a table works on any database. A file that is not
readable Parquet (cut short, overwritten) is left out of its view with a
:class:`~handdb.errors.DamagedFileWarning` naming it, so one damaged file never makes a
whole table unreadable; the next build writes it again. Derived
views in ``schemas/views/*.sql`` are created after the table views and the macros of
:func:`macro_statements`: ``mm_per_unit(units)``, which the ``*_mm`` views use to put every
clip's lengths in millimetres, and ``finger_rank(finger)``, to list fingers in anatomical
order.

A read-only connection (what :func:`query` and ``handdb sql`` use) is sealed with DuckDB's
own settings once the views exist: external access is off, so no statement reads or writes
any file (``COPY ... TO``, ``ATTACH``, ``EXPORT DATABASE``, ``read_csv``, extensions), and
the configuration is locked, so no statement turns it back on. DuckDB's catalog lives in
memory: a statement may create a table there, never a file.

The files are read by Arrow, not by DuckDB's own ``read_parquet``: a view over
``read_parquet`` opens its files when a statement runs, which the seal forbids, and
DuckDB's ``allowed_paths``, which would let it, lets ``COPY ... TO`` overwrite those very
files. A :class:`ParquetScan` gives DuckDB the Arrow stream protocol over
``pyarrow.parquet`` readers, without importing ``pyarrow.dataset``, which loads pandas
(0.3-0.5 s of ``handdb sql``'s start); DuckDB then reads every column of the files it
scans. A table of :data:`PRUNED_SCAN_BYTES` or more is scanned through a
``pyarrow.dataset`` instead, which reads only the columns a statement uses.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from functools import cache
from typing import TYPE_CHECKING, Any

import duckdb
import pyarrow as pa
import pyarrow.fs as pafs
import pyarrow.parquet as pq

from handdb.clip import METERS_PER_UNIT
from handdb.errors import DamagedFileWarning, QueryError
from handdb.hand.skeletons import FINGERS
from handdb.paths import SCHEMAS_DIR
from handdb.store import tables
from handdb.store.database import DAMAGE_ERRORS, Store

if TYPE_CHECKING:
    import pyarrow.dataset as ds

VIEWS_DIR = SCHEMAS_DIR / "views"

#: Bytes of a table's files from which its view scans a ``pyarrow.dataset``, reading only the
#: columns a statement uses, rather than a :class:`ParquetScan` of every column: about where
#: reading every column costs what importing ``pyarrow.dataset`` does (0.3-0.5 s). Measured
#: on 40 copies of the synthetic demo's ``joints_3d`` (99 MB): scans took 1.3-1.6 s longer
#: than with the columns pruned.
PRUNED_SCAN_BYTES = 25_000_000

#: DuckDB settings that seal a read-only connection, in order (the lock comes last).
READ_ONLY_SETTINGS: tuple[tuple[str, bool], ...] = (
    ("python_enable_replacements", False),
    ("enable_external_access", False),
    ("lock_configuration", True),
)


def arrow_filesystem(store: Store) -> pafs.FileSystem:
    """The store's filesystem as Arrow reads it."""
    if store.is_local:
        return pafs.LocalFileSystem()
    return pafs.PyFileSystem(pafs.FSSpecHandler(store.fs))


class ParquetScan:
    """The rows of some Parquet files in one schema, as an Arrow stream made anew per scan.

    DuckDB scans any object with the Arrow PyCapsule stream protocol
    (``__arrow_c_stream__``) and asks it for a fresh stream each time a statement reads
    the view made from it, so a view over a scan reads the files at that moment.

    Parameters
    ----------
    files
        Paths of the Parquet files on ``filesystem``, read in this order.
    schema
        The schema of the rows: the files' columns of these names, cast to its types.
    filesystem
        Where the files are.
    """

    def __init__(self, files: list[str], schema: pa.Schema,
                 filesystem: pafs.FileSystem) -> None:
        self.files = tuple(files)
        self.schema = schema
        self.filesystem = filesystem

    def batches(self) -> Iterator[pa.RecordBatch]:
        """Every file's record batches in turn, in :attr:`schema`.

        A column the file lacks (written under an older contract) is null, as a
        ``pyarrow.dataset`` over the same files gives it.
        """
        for path in self.files:
            reader = pq.ParquetFile(path, filesystem=self.filesystem)
            present = set(reader.schema_arrow.names)
            names = [name for name in self.schema.names if name in present]
            for batch in reader.iter_batches(columns=names):
                yield pa.RecordBatch.from_arrays(
                    [batch.column(f.name).cast(f.type) if f.name in present
                     else pa.nulls(batch.num_rows, f.type) for f in self.schema],
                    schema=self.schema)

    def __arrow_c_schema__(self) -> Any:
        """The rows' schema, as an Arrow C schema capsule."""
        return self.schema.__arrow_c_schema__()

    def __arrow_c_stream__(self, requested_schema: Any = None) -> Any:
        """A new stream of the rows, as an Arrow C stream capsule."""
        reader = pa.RecordBatchReader.from_batches(self.schema, self.batches())
        return reader.__arrow_c_stream__(requested_schema)


def table_rows(store: Store, table: str) -> ParquetScan | ds.Dataset:
    """The committed rows of ``table``: a scan of its readable files, in its contract schema.

    A :class:`ParquetScan`, or a ``pyarrow.dataset`` when the files hold
    :data:`PRUNED_SCAN_BYTES` or more. A file whose Parquet footer does not read is left
    out, with a :class:`~handdb.errors.DamagedFileWarning` naming it.
    """
    filesystem = arrow_filesystem(store)
    files = [path for path in store.table_files(table) if _readable(store, path, filesystem)]
    schema = tables.schema(table)
    if files and sum(info.size for info in filesystem.get_file_info(files)) >= PRUNED_SCAN_BYTES:
        import pyarrow.dataset

        return pyarrow.dataset.dataset(files, schema=schema, format="parquet",
                                       filesystem=filesystem)
    return ParquetScan(files, schema, filesystem)


def _readable(store: Store, path: str, filesystem: pafs.FileSystem) -> bool:
    """Whether the Parquet file at ``path`` opens; warn, naming it, when it does not."""
    try:
        pq.read_metadata(path, filesystem=filesystem)
    except DAMAGE_ERRORS as exc:
        warnings.warn(DamagedFileWarning(
            f"left out {store.uri(store.relative(path))}: it is damaged ({exc}); build the "
            "database again to write it from the inbox"), stacklevel=2)
        return False
    return True


def _quoted(text: str) -> str:
    """``text`` as a SQL string literal."""
    return "'" + text.replace("'", "''") + "'"


def macro_statements() -> str:
    """``CREATE MACRO`` statements for what the views and queries need from Python's tables.

    ``mm_per_unit(units)``: millimetres per unit of a length unit's name, made from
    :data:`handdb.clip.METERS_PER_UNIT` so SQL and Python agree on every unit a sidecar may
    name; an unknown name gives NULL, never a wrong length.
    ``finger_rank(finger)``: a finger's place from the thumb (0) to the little finger (4),
    :data:`handdb.hand.skeletons.FINGERS`, then ``palm``; ``ORDER BY finger_rank(finger)``
    lists fingers in anatomical order rather than alphabetically.
    """
    units = " ".join(f"WHEN {_quoted(unit)} THEN {metres * 1000!r}::DOUBLE"
                     for unit, metres in METERS_PER_UNIT.items())
    fingers = " ".join(f"WHEN {_quoted(finger)} THEN {rank}"
                       for rank, finger in enumerate((*FINGERS, "palm")))
    return (f"CREATE OR REPLACE MACRO mm_per_unit(units) AS CASE units {units} END;\n"
            f"CREATE OR REPLACE MACRO finger_rank(finger) AS CASE finger {fingers} END;")


#: A derived view named ``<table>_mm`` is ``<table>`` with its lengths in millimetres.
MM_SUFFIX = "_mm"


def _in_millimetres(column: str, doc: str) -> str:
    """A column's contract doc as it reads in a ``*_mm`` view, whose lengths are in mm."""
    if column == "units":
        return "mm: this view gives every length in millimetres"
    return (doc.replace("clip units", "mm").replace("pixels per unit", "pixels per mm")
            .replace(", units;", ", mm;"))


@cache
def derived_views() -> dict[str, str]:
    """The derived views of ``schemas/views``: name -> what the comment opening it says."""
    return {path.stem: path.read_text().splitlines()[0].removeprefix("--").strip()
            for path in sorted(VIEWS_DIR.glob("*.sql"))}


@cache
def comment_statements() -> str:
    """``COMMENT ON`` statements: every view's description and its columns' docs.

    Table views take them from their contracts (``schemas/tables``), derived views from
    their files' opening comment. DuckDB shows them in ``duckdb_views()`` and
    ``duckdb_columns()`` (``comment``).
    """
    statements = [f"COMMENT ON VIEW {name} IS {_quoted(text)}"
                  for name, text in derived_views().items()]
    for name in derived_views():
        base = name.removesuffix(MM_SUFFIX)
        if name.endswith(MM_SUFFIX) and base in tables.table_names():
            statements += [
                f"COMMENT ON COLUMN {name}.{field.name} IS "
                f"{_quoted(_in_millimetres(field.name, field.metadata[b'doc'].decode()))}"
                for field in tables.schema(base) if field.metadata and field.metadata.get(b"doc")]
    for name in tables.table_names():
        spec = tables.table_spec(name)
        statements.append(f"COMMENT ON VIEW {name} IS {_quoted(spec.description)}")
        statements += [
            f"COMMENT ON COLUMN {name}.{field.name} IS "
            f"{_quoted(field.metadata[b'doc'].decode())}"
            for field in spec.schema if field.metadata and field.metadata.get(b"doc")]
    return ";\n".join(statements) + ";"


def connect(db: str | Store, *, database: str = ":memory:", read_only: bool = False
            ) -> duckdb.DuckDBPyConnection:
    """Open a DuckDB connection with a view for every table of the database at ``db``.

    Parameters
    ----------
    db
        Database folder or fsspec URL, or a :class:`~handdb.store.database.Store`.
    database
        DuckDB's own database (in memory by default: the data stays in Parquet).
    read_only
        Seal the connection once the views exist (:data:`READ_ONLY_SETTINGS`): its
        statements can read the views and nothing else, and write no file.
    """
    store = db if isinstance(db, Store) else Store(str(db))
    con = duckdb.connect(database)
    for name in tables.table_names():
        con.from_arrow(table_rows(store, name)).create_view(name, replace=True)
    con.execute(macro_statements())
    for sql in sorted(VIEWS_DIR.glob("*.sql")):
        con.execute(sql.read_text())
    con.execute(comment_statements())
    if read_only:
        for name, value in READ_ONLY_SETTINGS:
            con.execute(f"SET {name} = {str(value).lower()}")
    return con


def query(db: str | Store, sql: str) -> pa.Table:
    """Run ``sql`` on a read-only connection to the database at ``db``; return the result.

    Raises
    ------
    DatabasePathError
        When there is no database at ``db``.
    QueryError
        When ``sql`` holds no statement with a result.
    duckdb.Error
        When DuckDB refuses the statement (a file access among them).
    """
    store = db if isinstance(db, Store) else Store(str(db))
    store.check_readable()
    with connect(store, read_only=True) as con:
        relation = con.sql(sql)
        if relation is None:
            raise QueryError(f"the statement {sql.strip()[:80]!r} holds no query: give one "
                             "with a result, e.g. 'SELECT clip_id, n_frames FROM clips'")
        return relation.to_arrow_table()
