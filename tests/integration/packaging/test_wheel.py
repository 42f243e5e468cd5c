"""The wheel works outside the repository, on the oldest dependencies it admits.

The package is built into a wheel, installed into a fresh virtual environment with every
dependency at the lowest version ``pyproject.toml`` allows (uv's ``lowest-direct``
resolution), and ``handdb demo`` runs there, in a folder far from the repository.
"""

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.support.paths import REPO

pytestmark = pytest.mark.slow


def _run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    done = subprocess.run(command, capture_output=True, text=True, **kwargs)
    assert done.returncode == 0, f"{' '.join(command)}\n{done.stdout[-3000:]}{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """A virtual environment holding the wheel and the lowest allowed dependencies."""
    root = tmp_path_factory.mktemp("wheel")
    _run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", str(REPO),
          "-w", str(root / "dist")])
    wheel, = (root / "dist").glob("handdb-*.whl")
    uv = Path(sys.executable).parent / "uv"
    venv = root / "venv"
    _run([str(uv), "venv", "--quiet", "--python", sys.executable, str(venv)])
    floors = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    _run([str(uv), "pip", "install", "--quiet", "--resolution", "lowest-direct", *floors,
          str(wheel)], env=os.environ | {"VIRTUAL_ENV": str(venv)})
    return venv


def test_the_wheel_carries_its_contracts_and_no_generic_module(installed):
    site, = (installed / "lib").glob("python3*/site-packages")
    assert (site / "handdb" / "schemas" / "tables" / "clips.json").is_file()
    assert (site / "handdb" / "schemas" / "skeletons" / "mediapipe21.json").is_file()
    assert (site / "handdb" / "py.typed").is_file()
    assert (site / "handdb_flows" / "build.py").is_file()
    assert not (site / "flows").exists()


def test_demo_builds_a_database_outside_the_repository(installed, tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PREFECT_HOME")}
    env["PREFECT_HOME"] = str(tmp_path / "prefect")
    handdb = installed / "bin" / "handdb"
    _run([str(handdb), "demo", "--inbox", "inbox", "--db", "db"], cwd=tmp_path, env=env)
    done = _run([str(handdb), "sql", "--db", "db", "--format", "csv",
                 "SELECT count(*) AS n FROM clips"], cwd=tmp_path, env=env)
    assert done.stdout.splitlines() == ["n", "8"]
