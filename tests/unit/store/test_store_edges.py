"""The store's edges: paths that look like patterns, links that leave the database, paths
that cannot hold a database, damaged files."""

import hashlib
import os
import re

import duckdb
import pytest

from handdb.errors import DamagedFileError, DamagedFileWarning, DatabasePathError, QueryError
from handdb.store.database import FILES_TABLE, LOCK_FILE, Store
from handdb.store.query import query
from tests.support.store_rows import clip_row, truth_rows


@pytest.fixture
def siblings(tmp_path):
    """A database at ``db[1]`` beside ``db1``, which its name matches as a glob pattern."""
    patterned, sibling = Store(str(tmp_path / "db[1]")), Store(str(tmp_path / "db1"))
    patterned.write("truth_3d", "a", truth_rows("a", 3))
    sibling.write("truth_3d", "b", truth_rows("b", 5))
    return patterned, sibling


def test_a_database_path_is_never_a_pattern(siblings, tmp_path):
    patterned, sibling = siblings
    left = tmp_path / "db1" / "truth_3d" / "b.parquet.0123.tmp"
    left.write_bytes(b"half written by a build of db1")
    assert patterned.remove_temporaries() == 0
    assert left.read_bytes() == b"half written by a build of db1"
    assert patterned.partition_keys("truth_3d") == ["a"]
    assert query(patterned, "SELECT count(*) AS n FROM truth_3d").to_pylist() == [{"n": 3}]
    assert sibling.remove_temporaries() == 1 and not left.exists()


@pytest.fixture
def outside(tmp_path):
    """A folder outside the database, holding a file a link inside the database points to."""
    folder = tmp_path / "elsewhere"
    folder.mkdir()
    (folder / "keep.txt").write_text("not the database's")
    return folder


def test_a_lock_file_that_is_a_link_is_refused_and_left_alone(tmp_path, outside):
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    (tmp_path / "db" / LOCK_FILE).symlink_to(outside / "keep.txt")
    with pytest.raises(DatabasePathError, match=r"db/\.lock is a symbolic link"):
        with store.lock():
            pass
    assert (outside / "keep.txt").read_text() == "not the database's"


def test_a_table_folder_that_is_a_link_is_never_written_or_cleaned_through(tmp_path, outside):
    store = Store(str(tmp_path / "db"))
    store.write("clips", "a", clip_row("a"))
    (tmp_path / "db" / "truth_3d").symlink_to(outside, target_is_directory=True)
    stray = outside / "b.parquet.0123.tmp"
    stray.write_bytes(b"someone else's")
    with pytest.raises(DatabasePathError, match=r"db/truth_3d is a symbolic link"):
        store.write("truth_3d", "a", truth_rows("a", 3))
    with pytest.raises(DatabasePathError, match=r"db/truth_3d is a symbolic link"):
        store.remove_temporaries()
    with pytest.raises(DatabasePathError, match=r"db/truth_3d is a symbolic link"):
        store.delete("truth_3d", "b")
    assert sorted(p.name for p in outside.iterdir()) == ["b.parquet.0123.tmp", "keep.txt"]
    assert stray.read_bytes() == b"someone else's"


def test_a_build_refuses_a_database_holding_a_link_before_it_writes(tmp_path, outside):
    store = Store(str(tmp_path / "db"))
    store.write("clips", "a", clip_row("a"))
    (tmp_path / "db" / "reports").mkdir()
    (tmp_path / "db" / "reports" / "a").symlink_to(outside, target_is_directory=True)
    with pytest.raises(DatabasePathError, match=r"db/reports/a is a symbolic link.*replace"):
        with store.lock():
            store.write("truth_3d", "a", truth_rows("a", 3))
    assert not (tmp_path / "db" / "truth_3d").exists()


def test_the_database_folder_itself_may_be_a_link(tmp_path):
    (tmp_path / "real").mkdir()
    (tmp_path / "db").symlink_to(tmp_path / "real", target_is_directory=True)
    store = Store(str(tmp_path / "db"))
    with store.lock():
        store.write("truth_3d", "a", truth_rows("a", 3))
    assert (tmp_path / "real" / "truth_3d" / "a.parquet").is_file()


def test_a_file_where_the_database_belongs_is_refused(tmp_path):
    (tmp_path / "db").write_text("a file")
    store = Store(str(tmp_path / "db"))
    with pytest.raises(DatabasePathError, match=r"database path .*db is a file.*--db"):
        with store.lock():
            pass
    with pytest.raises(DatabasePathError, match=r"db is a file, not a database folder"):
        store.check_readable()
    assert (tmp_path / "db").read_text() == "a file"


@pytest.mark.parametrize("parent", ["missing", "afile"])
def test_a_database_whose_parent_is_missing_or_a_file_is_refused(tmp_path, parent):
    (tmp_path / "afile").write_text("")
    store = Store(str(tmp_path / parent / "db"))
    with pytest.raises(DatabasePathError, match=rf"its parent .*{parent} (does not exist|is a "
                       r"file); create that folder first"):
        with store.lock():
            pass
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="needs a user the file permissions apply to")
def test_an_unwritable_database_folder_is_refused(tmp_path):
    folder = tmp_path / "db"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(DatabasePathError, match=r"cannot write in the database folder"):
            with Store(str(folder)).lock():
                pass
    finally:
        folder.chmod(0o700)


@pytest.mark.parametrize("make", [lambda p: None, lambda p: p.mkdir()],
                         ids=["missing", "not-a-database"])
def test_querying_no_database_is_refused(tmp_path, make):
    make(tmp_path / "db")
    with pytest.raises(DatabasePathError, match=r"build one with 'handdb build --db"):
        Store(str(tmp_path / "db")).check_readable()


@pytest.fixture
def stored(tmp_path):
    """A database with one ``truth_3d`` partition, and a file outside it to read."""
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    (tmp_path / "secret.csv").write_text("a,b\n1,2\n")
    return store


@pytest.mark.parametrize("statement", [
    "COPY (SELECT * FROM truth_3d WHERE frame = 0) TO '{db}/truth_3d/a.parquet' (FORMAT parquet)",
    "COPY truth_3d TO '{tmp}/out.csv'",
    "EXPORT DATABASE '{db}/exported'",
    "ATTACH '{db}/attached.duckdb' AS other",
    "SELECT * FROM read_csv('{tmp}/secret.csv')",
    "SELECT * FROM read_parquet('{db}/truth_3d/a.parquet')",
    "SET enable_external_access = true",
    "RESET lock_configuration",
])
def test_a_query_touches_no_file(stored, tmp_path, statement):
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    original = (tmp_path / "db" / "truth_3d" / "a.parquet").read_bytes()
    with pytest.raises(duckdb.Error, match="disabled|Cannot change configuration"):
        query(stored, statement.format(db=tmp_path / "db", tmp=tmp_path))
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before
    assert (tmp_path / "db" / "truth_3d" / "a.parquet").read_bytes() == original
    assert query(stored, "SELECT count(*) AS n FROM truth_3d").to_pylist() == [{"n": 3}]


@pytest.mark.parametrize("statement", ["", "   ", ";", "-- only a comment"])
def test_a_statement_without_a_query_is_refused_with_a_message(stored, statement):
    with pytest.raises(QueryError, match="holds no query: give one with a result"):
        query(stored, statement)


@pytest.fixture
def committed(tmp_path):
    """Two committed clips, ``a`` and ``b``, with their ``truth_3d`` rows."""
    store = Store(str(tmp_path / "db"))
    for clip_id, n_frames in (("a", 3), ("b", 5)):
        store.commit_clip(clip_id, {"clips": clip_row(clip_id),
                                    "truth_3d": truth_rows(clip_id, n_frames)})
    return store


def test_a_commit_records_every_file_with_its_size_and_checksum(committed, tmp_path):
    record = committed.read(FILES_TABLE, "a").to_pylist()
    assert [r["file"] for r in record] == ["clips/a.parquet", "truth_3d/a.parquet"]
    for row in record:
        data = (tmp_path / "db" / row["file"]).read_bytes()
        assert row["bytes"] == len(data)
        assert row["sha256"] == hashlib.sha256(data).hexdigest()
    assert committed.clip_damage("a") is None and committed.clip_damage("b") is None


def _flip_a_byte(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(("damage", "said"), [
    (lambda p: p.unlink(), r"truth_3d/a\.parquet is missing"),
    (lambda p: p.write_bytes(p.read_bytes()[:-20]),
     r"truth_3d/a\.parquet is damaged \(it has changed size.*\)"),
    (_flip_a_byte, r"truth_3d/a\.parquet is damaged \(its checksum differs.*\)"),
])
def test_a_missing_or_damaged_file_is_noticed(committed, tmp_path, damage, said):
    damage(tmp_path / "db" / "truth_3d" / "a.parquet")
    assert re.fullmatch(said, committed.clip_damage("a"))
    assert committed.clip_damage("b") is None


def test_a_clip_without_a_record_of_its_files_is_not_trusted(committed, tmp_path):
    (tmp_path / "db" / FILES_TABLE / "a.parquet").unlink()
    assert committed.clip_damage("a") == "the record of its files, clip_files/a.parquet, is missing"


def test_one_damaged_file_leaves_the_rest_of_its_table_readable(committed, tmp_path):
    damaged = tmp_path / "db" / "truth_3d" / "a.parquet"
    damaged.write_bytes(damaged.read_bytes()[:-20])
    with pytest.warns(DamagedFileWarning, match=r"left out .*truth_3d/a\.parquet: it is damaged"):
        result = query(committed, "SELECT clip_id, count(*) AS n FROM truth_3d GROUP BY clip_id")
    assert result.to_pylist() == [{"clip_id": "b", "n": 5}]
    with pytest.raises(DamagedFileError, match=r"truth_3d/a\.parquet is damaged"):
        committed.read_table("truth_3d")
    keys = committed.clip_build_keys()
    (tmp_path / "db" / "clips" / "b.parquet").write_bytes(b"not parquet")
    assert keys == {"a": "k1", "b": "k1"} and committed.clip_build_keys() == {"a": "k1"}
