import multiprocessing
import sys
import threading
from importlib import import_module

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from handdb.errors import DatabaseLockedError, SchemaError, StoreError
from handdb.store import tables
from handdb.store.database import CLIP_TABLES, LOCK_FILE, Store, encode
from handdb.store.query import connect, query
from tests.support.store_rows import clip_row, truth_rows

#: The module itself (``handdb.store.query`` the attribute is its function ``query``).
query_module = import_module("handdb.store.query")


def test_commit_clip_writes_tables_and_marks_completion(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 3)})
    assert store.clip_build_keys() == {"a": "k1"}
    assert store.read("truth_3d", "a").num_rows == 3
    assert pq.read_schema(store.partition_path("truth_3d", "a")).names == \
        tables.schema("truth_3d").names


def test_recommit_replaces_the_clip_and_drops_tables_it_no_longer_has(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 3)})
    store.commit_clip("b", {"clips": clip_row("b"), "truth_3d": truth_rows("b", 2)})
    store.commit_clip("a", {"clips": clip_row("a", "k2")})
    assert store.read("truth_3d", "a") is None
    assert store.read("truth_3d", "b").num_rows == 2
    assert store.clip_build_keys() == {"a": "k2", "b": "k1"}


def test_identical_writes_give_identical_bytes(tmp_path):
    store = Store(str(tmp_path / "db"))
    path = store.write("truth_3d", "a", truth_rows("a", 50))
    first = open(path, "rb").read()
    store.write("truth_3d", "a", truth_rows("a", 50))
    assert open(path, "rb").read() == first


def test_bad_rows_leave_stored_data_untouched(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 3)})
    before = {p: open(p, "rb").read() for p in store.fs.glob(store.path("*", "*.parquet"))}
    broken = truth_rows("a", 5).drop_columns(["z"])
    with pytest.raises(SchemaError):
        store.commit_clip("a", {"clips": clip_row("a", "k9"), "truth_3d": broken})
    after = {p: open(p, "rb").read() for p in store.fs.glob(store.path("*", "*.parquet"))}
    assert after == before
    with pytest.raises(StoreError, match="no 'clips' row"):
        store.commit_clip("a", {"truth_3d": truth_rows("a", 3)})


def test_temporaries_are_invisible_and_cleaned(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    (tmp_path / "db" / "truth_3d" / "b.parquet.123.tmp").write_bytes(b"half written")
    assert query(store, "SELECT count(*) AS n FROM truth_3d").column("n")[0].as_py() == 3
    assert store.remove_temporaries() == 1
    assert not list((tmp_path / "db" / "truth_3d").glob("*.tmp"))


def _hold_lock(url, ready, release):
    with Store(url).lock():
        ready.set()
        release.wait(30)


def test_second_builder_gets_a_clear_message(tmp_path):
    url = str(tmp_path / "db")
    ctx = multiprocessing.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    holder = ctx.Process(target=_hold_lock, args=(url, ready, release))
    holder.start()
    try:
        assert ready.wait(60)
        with pytest.raises(DatabaseLockedError, match=r"being built by pid \d+"):
            with Store(url).lock():
                pass
    finally:
        release.set()
        holder.join(30)
    with Store(url).lock():  # released when the holder ended
        pass


@pytest.mark.skipif(sys.platform == "win32", reason="flock is POSIX")
def test_a_builder_refused_before_the_holder_wrote_its_pid_still_names_it(tmp_path):
    """The holder takes the lock, then writes who it is; a build refused in between waits."""
    import fcntl

    url = str(tmp_path / "db")
    with Store(url).lock():
        pass  # creates the database folder and its lock file
    lock_path = tmp_path / "db" / LOCK_FILE
    with open(lock_path, "r+") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        writer = threading.Timer(0.05, lambda: lock_path.write_text("pid 4242 on elsewhere"))
        writer.start()
        try:
            with pytest.raises(DatabaseLockedError, match="being built by pid 4242 on elsewhere"):
                with Store(url).lock():
                    pass
        finally:
            writer.join()


def test_lock_is_released_when_the_holder_is_killed(tmp_path):
    url = str(tmp_path / "db")
    ctx = multiprocessing.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    holder = ctx.Process(target=_hold_lock, args=(url, ready, release))
    holder.start()
    assert ready.wait(60)
    holder.kill()
    holder.join(30)
    with Store(url).lock():
        pass


def test_views_exist_for_every_table_even_when_empty(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 3)})
    with connect(store) as con:
        names = {row[0] for row in con.sql("SELECT view_name FROM duckdb_views() "
                                           "WHERE NOT internal").fetchall()}
        assert set(tables.table_names()) <= names
        assert {"clip_summary", "depth_error"} <= names
        assert con.sql("SELECT count(*) FROM joints_3d").fetchall() == [(0,)]
        assert con.sql("SELECT sum(x) FROM truth_3d").fetchall() == [(3.0,)]


@pytest.mark.parametrize("pruned_from", [query_module.PRUNED_SCAN_BYTES, 0],
                         ids=["parquet-scan", "pyarrow-dataset"])
def test_a_view_gives_the_same_rows_at_every_scan_either_way_it_reads(tmp_path, monkeypatch,
                                                                      pruned_from):
    monkeypatch.setattr(query_module, "PRUNED_SCAN_BYTES", pruned_from)
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    store.write("truth_3d", "b", truth_rows("b", 2, offset=10.0))
    rows = query_module.table_rows(store, "truth_3d")
    assert isinstance(rows, query_module.ParquetScan) == (pruned_from > 0)
    with connect(store, read_only=True) as con:
        scan = "SELECT clip_id, count(*), sum(x) FROM truth_3d GROUP BY ALL ORDER BY ALL"
        assert con.sql(scan).fetchall() == con.sql(scan).fetchall() == [
            ("a", 3, 3.0), ("b", 2, 21.0)]
        assert con.sql("SELECT typeof(frame), typeof(x) FROM truth_3d LIMIT 1").fetchall() == \
            [("INTEGER", "DOUBLE")]


@pytest.mark.parametrize("pruned_from", [query_module.PRUNED_SCAN_BYTES, 0],
                         ids=["parquet-scan", "pyarrow-dataset"])
def test_a_file_of_an_older_contract_reads_its_missing_column_as_null(tmp_path, monkeypatch,
                                                                       pruned_from):
    monkeypatch.setattr(query_module, "PRUNED_SCAN_BYTES", pruned_from)
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    [path] = store.table_files("truth_3d")
    pq.write_table(pq.read_table(path).drop_columns(["z"]), path)
    with connect(store, read_only=True) as con:
        assert con.sql("SELECT count(*), count(z), sum(x) FROM truth_3d").fetchall() == [
            (3, 0, 3.0)]


def test_remote_filesystem_url(tmp_path):
    store = Store("memory://handdb-test-db")
    store.commit_clip("a", {"clips": clip_row("a"), "truth_3d": truth_rows("a", 4)})
    assert store.clip_build_keys() == {"a": "k1"}
    result = query(store, "SELECT count(*) AS n, max(x) AS m FROM truth_3d")
    assert result.to_pylist() == [{"n": 4, "m": 3.0}]
    with store.lock():
        with pytest.raises(DatabaseLockedError, match="lock file"):
            with Store("memory://handdb-test-db").lock():
                pass
    with store.lock():
        pass


def test_clip_tables_are_the_per_clip_contracts():
    assert "clips" in CLIP_TABLES and "joints_3d" in CLIP_TABLES
    assert "runs" not in CLIP_TABLES and "quarantine" not in CLIP_TABLES


def test_store_reads_back_in_contract_order(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    assert store.read_table("truth_3d").schema == tables.schema("truth_3d")


def test_macros_order_fingers_anatomically_and_scale_units_to_mm(tmp_path):
    from handdb.clip import METERS_PER_UNIT
    from handdb.hand.skeletons import FINGERS

    store = Store(str(tmp_path / "db"))
    store.commit_clip("a", {"clips": clip_row("a")})
    with connect(store) as con:
        fingers = con.sql("SELECT f FROM (VALUES ('little'), ('index'), ('ring'), ('thumb'), "
                          "('palm'), ('middle')) AS t(f) ORDER BY finger_rank(f)").fetchall()
        scale = {unit: con.execute("SELECT mm_per_unit(?)", [unit]).fetchone()[0]
                 for unit in (*METERS_PER_UNIT, "furlong")}
    assert [f for (f,) in fingers] == [*FINGERS, "palm"]
    assert scale == {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "furlong": None}


def test_only_string_columns_are_dictionary_encoded_and_the_rows_read_back():
    rows = truth_rows("c", 3)
    parquet = pq.ParquetFile(pa.BufferReader(encode(rows)))
    encodings = {parquet.metadata.row_group(0).column(i).path_in_schema:
                 parquet.metadata.row_group(0).column(i).encodings
                 for i in range(parquet.metadata.num_columns)}
    strings = {f.name for f in rows.schema if pa.types.is_string(f.type)}
    assert strings == {"clip_id", "joint"}
    for column, used in encodings.items():
        assert ("RLE_DICTIONARY" in used) == (column in strings), column
    assert parquet.read().equals(rows)
