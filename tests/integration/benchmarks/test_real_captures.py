"""The real-hands benchmark runs end to end and reports every dataset it has data for."""

import pytest

from tests.support.benchmarks import benchmark_module
from tests.support.paths import DHG_SAMPLE, REAL_TOOLS


@pytest.fixture(scope="module")
def bench():
    """``benchmarks/real_captures.py`` as a module."""
    with benchmark_module("real_captures") as module:
        yield module


def test_the_quick_run_writes_every_table(bench, tmp_path, capsys):
    out = tmp_path / "RESULTS-real.md"
    bench.main(["--quick", "--out", str(out)])
    text = out.read_text()
    assert text == capsys.readouterr().out
    assert "## Synthetic population" in text
    for method in bench.METHODS:
        assert f"| {method} |" in text
    for camera in bench.CAMERAS:
        assert f"**{camera}**" in text
    lifting, tools = text.split("## Real tool outputs without truth")
    sections = lifting.count("## ") - lifting.count("Skipped:")
    assert lifting.count("Bones where the default's sign accuracy is below") == sections
    if REAL_TOOLS.is_dir() and DHG_SAMPLE.is_file():
        # every stored clip has a verdict, and the refused files their reasons
        assert "| signer | openpose |" in tools and "| dhg | dhg |" in tools
        assert "| kistler.c3d | POINT:USED |" in tools
        assert tools.count("| plausible |") + tools.count("| flagged: ") == 5
    assert "Constants: tuned" in text and "(--quick)" in text
    if DHG_SAMPLE.is_file():
        assert "## DHG in its own view" in text
    if (REAL_TOOLS / "interhand").is_dir():
        assert "pseudo-clips" in text and "held out" in text
