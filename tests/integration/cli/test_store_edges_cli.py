"""The command line at the store's edges: database paths it cannot use, queries that would
write, statements that say nothing."""

from typer.testing import CliRunner

from handdb.cli import EXIT_FAILED, app
from handdb.store.database import Store
from tests.support.store_rows import truth_rows

runner = CliRunner()


def _refused(result, *fragments):
    assert result.exit_code == EXIT_FAILED, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in result.output


def test_build_into_a_file_is_refused_with_a_message(tmp_path):
    (tmp_path / "inbox").mkdir()
    (tmp_path / "db").write_text("a file")
    result = runner.invoke(app, ["build", "--inbox", str(tmp_path / "inbox"),
                                 "--db", str(tmp_path / "db"), "--runner", "local"])
    _refused(result, str(tmp_path / "db"), "is a file", "--db")


def test_build_into_a_missing_parent_is_refused_with_a_message(tmp_path):
    (tmp_path / "inbox").mkdir()
    db = tmp_path / "nowhere" / "db"
    result = runner.invoke(app, ["build", "--inbox", str(tmp_path / "inbox"), "--db", str(db),
                                 "--runner", "local"])
    _refused(result, str(tmp_path / "nowhere"), "does not exist")
    assert not (tmp_path / "nowhere").exists()


def test_sql_on_a_missing_database_is_an_error_not_an_empty_table(tmp_path):
    result = runner.invoke(app, ["sql", "--db", str(tmp_path / "db"), "SELECT * FROM clips"])
    _refused(result, "no database at", "handdb build --db")


def test_sql_on_a_file_is_an_error(tmp_path):
    (tmp_path / "db").write_text("a file")
    result = runner.invoke(app, ["sql", "--db", str(tmp_path / "db"), "SELECT 1"])
    _refused(result, "is a file")


def test_sql_with_an_empty_statement_says_so(tmp_path):
    (tmp_path / "db" / "clips").mkdir(parents=True)
    result = runner.invoke(app, ["sql", "--db", str(tmp_path / "db"), " "])
    _refused(result, "holds no query")


def test_sql_cannot_write_into_the_database(tmp_path):
    (tmp_path / "db" / "clips").mkdir(parents=True)
    target = tmp_path / "db" / "clips" / "x.parquet"
    result = runner.invoke(app, ["sql", "--db", str(tmp_path / "db"),
                                 f"COPY (SELECT 1 AS a) TO '{target}' (FORMAT parquet)"])
    _refused(result, "SQL error", "disabled")
    assert not target.exists()


def test_sql_leaves_a_damaged_file_out_and_names_it(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", truth_rows("a", 3))
    store.write("truth_3d", "b", truth_rows("b", 5))
    (tmp_path / "db" / "truth_3d" / "a.parquet").write_bytes(b"cut sho")
    result = runner.invoke(app, ["sql", "--db", str(tmp_path / "db"), "-f", "csv",
                                 "SELECT count(*) AS n FROM truth_3d"])
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines() == ["n", "5"]
    assert "warning:" in result.stderr and "truth_3d/a.parquet: it is damaged" in result.stderr
