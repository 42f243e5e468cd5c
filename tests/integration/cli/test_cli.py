"""The command line on a real database: sql output formats, help, exit statuses."""

import csv
import io
import json

import pytest
from typer.testing import CliRunner

from handdb.cli import EXIT_QUARANTINED, app
from handdb.store import tables
from handdb.store.database import Store
from handdb.store.query import derived_views

runner = CliRunner()


@pytest.fixture
def db(tmp_path):
    store = Store(str(tmp_path / "db"))
    store.write("truth_3d", "a", tables.from_columns("truth_3d", {
        "clip_id": "a", "frame": [0, 1, 2], "joint": ["wrist"] * 3, "joint_index": [0] * 3,
        "x": [1.5, 2.5, 3.5], "y": [0.0] * 3, "z": [10.0] * 3}))
    return str(tmp_path / "db")


def test_sql_csv_is_a_header_then_rows(db):
    result = runner.invoke(app, ["sql", "--db", db, "--format", "csv",
                                 "SELECT frame, x FROM truth_3d ORDER BY frame"])
    assert result.exit_code == 0, result.output
    rows = list(csv.reader(io.StringIO(result.stdout)))
    assert rows == [["frame", "x"], ["0", "1.5"], ["1", "2.5"], ["2", "3.5"]]


def test_sql_json_and_table(db):
    result = runner.invoke(app, ["sql", "--db", db, "-f", "json",
                                 "SELECT sum(x) AS total FROM truth_3d"])
    assert json.loads(result.stdout) == [{"total": 7.5}]
    result = runner.invoke(app, ["sql", "--db", db, "SELECT count(*) AS n FROM truth_3d"])
    assert result.exit_code == 0 and "3" in result.stdout and "n" in result.stdout


def test_sql_reads_the_database_from_the_environment(db):
    result = runner.invoke(app, ["sql", "-f", "csv", "SELECT count(*) AS n FROM truth_3d"],
                           env={"HANDDB_DB": db})
    assert result.stdout.splitlines() == ["n", "3"]


def test_sql_error_is_reported_not_raised(db):
    result = runner.invoke(app, ["sql", "--db", db, "SELECT nope FROM truth_3d"])
    assert result.exit_code == 1
    assert "SQL error" in result.output and "nope" in result.output


@pytest.mark.parametrize("command", [[], ["build"], ["sql"], ["serve"], ["demo"],
                                     ["ratios", "place"], ["export-usd"], ["export-bvh"],
                                     ["preview"]])
def test_every_command_explains_itself(command):
    result = runner.invoke(app, [*command, "--help"])
    assert result.exit_code == 0
    assert "Usage" in result.output and len(result.output.splitlines()) > 5


def test_serve_needs_exactly_one_schedule():
    result = runner.invoke(app, ["serve"])
    assert result.exit_code == 2 and "exactly one" in result.output


def test_build_exit_status_when_input_is_quarantined(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "good", seed=1)
    write_clip(inbox, "bad", seed=2)
    (inbox / "bad.clip.json").write_text('{"skeleton": "no-such-skeleton"}')
    result = runner.invoke(app, ["build", "--inbox", str(inbox), "--db", str(tmp_path / "db"),
                                 "--no-usd"])
    assert result.exit_code == EXIT_QUARANTINED, result.output
    assert "quarantined" in result.output and "bad.clip.json" in result.output
    assert "1 processed" in result.output


@pytest.fixture
def long_db(tmp_path):
    store = Store(str(tmp_path / "db"))
    n = 500
    store.write("truth_3d", "a", tables.from_columns("truth_3d", {
        "clip_id": "a", "frame": list(range(n)), "joint": ["wrist"] * n,
        "joint_index": [0] * n, "x": [0.5] * n, "y": [0.0] * n, "z": [10.0] * n}))
    return str(tmp_path / "db")


def table_lines(output: str) -> list[str]:
    """The lines of a printed table that hold a row of values."""
    return [line for line in output.splitlines() if line.startswith("│") and "wrist" in line]


def test_sql_table_shows_a_capped_number_of_rows_and_says_how_many(long_db):
    result = runner.invoke(app, ["sql", "--db", long_db, "--max-rows", "10",
                                 "SELECT * FROM truth_3d ORDER BY frame"])
    assert result.exit_code == 0, result.output
    assert len(table_lines(result.stdout)) == 10
    assert "500 rows (10 shown)" in result.stdout
    every = runner.invoke(app, ["sql", "--db", long_db, "--max-rows", "0",
                                "SELECT * FROM truth_3d"])
    assert len(table_lines(every.stdout)) == 500


def test_sql_table_prints_null_as_null_and_reads_the_query_from_stdin(db):
    result = runner.invoke(app, ["sql", "--db", db, "-"],
                           input="SELECT NULL AS nothing, true AS yes FROM truth_3d LIMIT 1")
    assert result.exit_code == 0, result.output
    [row] = [line for line in result.stdout.splitlines() if "NULL" in line and "│" in line]
    assert "true" in row and "True" not in row


def test_sql_vertical_prints_one_line_per_column(db):
    result = runner.invoke(app, ["sql", "--db", db, "--vertical",
                                 "SELECT clip_id, frame, x FROM truth_3d LIMIT 1"])
    assert result.exit_code == 0, result.output
    lines = [line for line in result.stdout.splitlines() if line.startswith("│")]
    assert [line.split("│")[1].strip() for line in lines[1:]] == ["clip_id", "frame", "x"]


def test_tables_lists_every_table_and_view_with_its_description():
    from handdb.store.query import derived_views

    result = runner.invoke(app, ["tables"])
    assert result.exit_code == 0, result.output
    for name in [*tables.table_names(), *derived_views()]:
        assert name in result.stdout
    assert "_rows" not in result.stdout


def test_describe_prints_a_tables_columns_with_their_docs():
    result = runner.invoke(app, ["describe", "joints_3d"])
    assert result.exit_code == 0, result.output
    for field in tables.schema("joints_3d"):
        assert field.name in result.stdout
    doc = tables.schema("joints_3d").field("z").metadata[b"doc"].decode()
    assert all(word in result.stdout for word in doc.split())  # wrapped in its cell
    unknown = runner.invoke(app, ["describe", "joint_3d"])
    assert unknown.exit_code == 1 and "joints_3d" in unknown.output


def test_describe_gives_an_mm_views_columns_their_docs_in_mm(db):
    result = runner.invoke(app, ["describe", "joints_3d_mm", "--db", db])
    assert result.exit_code == 0, result.output
    for field in tables.schema("joints_3d"):
        assert field.name in result.stdout
    assert "pixels per mm" in result.stdout and "clip units" not in result.stdout


def test_views_carry_the_contracts_comments_and_show_tables_lists_no_internals(db):
    result = runner.invoke(app, ["sql", "--db", db, "-f", "json",
                                 "SELECT comment FROM duckdb_columns() WHERE "
                                 "table_name = 'truth_3d' AND column_name = 'x'"])
    [row] = json.loads(result.stdout)
    assert row["comment"] == tables.schema("truth_3d").field("x").metadata[b"doc"].decode()
    shown = runner.invoke(app, ["sql", "--db", db, "-f", "csv", "SHOW TABLES"])
    names = shown.stdout.split()[1:]
    assert sorted(names) == sorted([*tables.table_names(), *derived_views()])
    assert {"clip_summary", "depth_error", "joints_3d_mm"} <= set(derived_views())
