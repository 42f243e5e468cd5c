"""Shared test configuration: a quiet, isolated Prefect, and shared data fixtures."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"

# Prefect reads these when it is first imported: set them before any test module does.
# Each xdist worker gets its own PREFECT_HOME (processes sharing a new database race on
# creating it); homes persist under .prefect/ so later runs reuse their databases.
_worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
_prefect_home = REPO / ".prefect" / f"test-{_worker}"
_prefect_home.mkdir(parents=True, exist_ok=True)
os.environ["PREFECT_HOME"] = str(_prefect_home)
os.environ.setdefault("PREFECT_SERVER_ANALYTICS_ENABLED", "false")
os.environ.setdefault("PREFECT_SERVER_LOGGING_LEVEL", "CRITICAL")
os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
os.environ.setdefault("PREFECT_SERVER_EPHEMERAL_STARTUP_TIMEOUT_SECONDS", "90")
os.environ.pop("PREFECT_API_URL", None)


@pytest.fixture(scope="session")
def dhg_sample() -> Path:
    """The real DHG capture in ../shared/data/dhg-sample; skips when it is absent."""
    path = SHARED_DATA / "dhg-sample" / "skeletons_world.txt"
    if not path.is_file():
        pytest.skip(f"shared data not present: {path}")
    return path
