from pathlib import Path

from typer.testing import CliRunner

from handdb.cli.ratios import app
from handdb.ingest.xray import read_xray
from handdb.lengths.ratios import joint_ratios
from handdb.store.database import Store

runner = CliRunner()


def test_place_uses_table1_without_a_database(tmp_path):
    result = runner.invoke(app, ["place", "--finger", "index", "--total", "1000",
                                 "--db", str(tmp_path / "none")], terminal_width=200)
    assert result.exit_code == 0, result.output
    assert "Table 1" in result.output
    for figure in ("484.6", "472.8", "504.7", "31.9"):
        assert figure in result.output


def test_place_reads_the_database(tmp_path: Path):
    xray = tmp_path / "one.xray.csv"
    xray.write_text("image_id,finger,segment,length\n"
                    "a,index,J1,50\na,index,J2,30\na,index,J3,20\n")
    db = tmp_path / "db"
    Store(str(db)).write("joint_ratios", "joint_ratios", joint_ratios(read_xray(xray)[0]))
    result = runner.invoke(app, ["place", "--finger", "index", "--total", "200",
                                 "--db", str(db)], terminal_width=200)
    assert result.exit_code == 0, result.output
    assert f"database {db}" in result.output
    assert "100.0" in result.output and "60.0" in result.output


def test_place_refuses_an_unknown_finger(tmp_path):
    result = runner.invoke(app, ["place", "--finger", "pointer", "--total", "10",
                                 "--db", str(tmp_path)])
    assert result.exit_code == 2
    assert "unknown finger" in result.output


def test_show_states_the_discrepancies(tmp_path):
    result = runner.invoke(app, ["show", "--db", str(tmp_path)], terminal_width=200)
    assert result.exit_code == 0, result.output
    assert "0.4946" in result.output and "0.4846" in result.output
    assert "169.97" in result.output and "169.67" in result.output
    cells = [line.replace("│", " ").split() for line in result.output.splitlines()]
    listed = [row[0] for row in cells if len(row) > 1 and row[1] == "J1"]
    assert listed == ["thumb", "index", "middle", "ring", "little"]
