"""The demo database, built once per session for the notebooks."""

from pathlib import Path

import pytest
from handdb_flows.settings import quick_flows

from handdb.demo import write_demo_inbox
from tests.support.building import run


@pytest.fixture(scope="session")
def demo_db(tmp_path_factory) -> Path:
    """A database built from the demo inbox, as ``make demo`` builds it."""
    root = tmp_path_factory.mktemp("demo")
    write_demo_inbox(root / "inbox")
    with quick_flows():
        summary = run(str(root / "inbox"), str(root / "db"), workers=2, runner="local")
    assert summary.ok and not summary.refusals, summary
    return root / "db"
