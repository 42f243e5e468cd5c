"""The store's edges: paths that look like patterns, links that leave the database, paths
that cannot hold a database, damaged files."""

import os

import duckdb
import pytest

from handdb.errors import DatabasePathError, QueryError
from handdb.store.database import LOCK_FILE, Store
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
