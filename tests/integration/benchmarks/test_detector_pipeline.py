"""The detector-input benchmark runs end to end and reports every dataset it has data for."""

import pytest

from tests.support.benchmarks import benchmark_module
from tests.support.paths import DHG_SAMPLE, REAL_TOOLS


@pytest.fixture(scope="module")
def bench():
    """``benchmarks/detector_pipeline.py`` as a module."""
    with benchmark_module("detector_pipeline") as module:
        yield module


def test_the_quick_run_writes_every_table(bench, tmp_path, capsys):
    out = tmp_path / "RESULTS-detector.md"
    bench.main(["--quick", "--out", str(out)])
    text = out.read_text()
    assert text == capsys.readouterr().out
    assert "(--quick)" in text and "## Synthetic population" in text
    measured = text.count("## ") - text.count("Skipped:") - 1
    for label, *_ in bench.VARIANTS:
        assert text.count(f"| {label} |") == measured
    assert text.count("Estimated lengths (five given)") == measured
    verdicts = text.split("## Targets")[1]
    assert verdicts.count(" met |\n") == measured
    if DHG_SAMPLE.is_file():
        assert "## DHG in its own view" in text and "| DHG in 1 random views |" in verdicts
    else:
        assert "## DHG\n" in text
    if (REAL_TOOLS / "interhand").is_dir():
        assert "pseudo-clips" in verdicts and "held out" in text
    else:
        assert "## InterHand2.6M\n" in text
