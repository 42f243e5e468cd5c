from typer.testing import CliRunner

from handdb.cli.lift import app


def test_compare_prints_every_method_and_writes_a_chart(tmp_path):
    chart = tmp_path / "thesis.png"
    result = CliRunner().invoke(app, ["compare", "--synthetic", "thesis", "--chart", str(chart)],
                                terminal_width=200)
    assert result.exit_code == 0, result.output
    for method in ("kinematic", "thesis", "thesis-nocheck"):
        assert method in result.output
    assert "palm_fold" in result.output
    assert chart.read_bytes()[:4] == b"\x89PNG"


def test_compare_needs_a_clip():
    result = CliRunner().invoke(app, ["compare"])
    assert result.exit_code != 0
