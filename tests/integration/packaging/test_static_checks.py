"""The library and its flows type-check and the repository lints clean, as ``make lint`` checks.

Both run in a subprocess on the repository's sources; a failure shows the tool's report.
"""

import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.paths import REPO

pytestmark = pytest.mark.slow

TOOLS = Path(sys.executable).parent


def _check(command: list[str]) -> None:
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0, f"{' '.join(command)}\n{done.stdout[-4000:]}{done.stderr[-2000:]}"


def test_library_type_checks(tmp_path):
    _check([str(TOOLS / "mypy"), "--cache-dir", str(tmp_path / "mypy-cache"), "handdb",
            "flows"])


def test_sources_lint_clean():
    _check([str(TOOLS / "ruff"), "check", "--no-cache", "handdb", "flows", "tests",
            "benchmarks", "notebooks"])
