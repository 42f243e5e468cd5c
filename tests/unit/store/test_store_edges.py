"""The store's edges: paths that look like patterns, links that leave the database, paths
that cannot hold a database, damaged files."""

import pytest

from handdb.store.database import Store
from handdb.store.query import query
from tests.support.store_rows import truth_rows


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
