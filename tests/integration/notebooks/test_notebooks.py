"""The notebooks run from top to bottom against the demo database, without an error."""


import nbformat
import pytest
from nbclient import NotebookClient

from tests.support.paths import REPO

pytestmark = pytest.mark.slow

NOTEBOOKS = REPO / "notebooks"
#: Seconds a single cell may run.
CELL_TIMEOUT_S = 600


@pytest.mark.parametrize("name", ["tour.ipynb", "bone_ratios.ipynb"])
def test_notebook_runs_against_the_demo_database(name, demo_db, tmp_path, monkeypatch):
    book = nbformat.read(NOTEBOOKS / name, as_version=4)
    assert all(not cell.get("outputs") for cell in book.cells if cell.cell_type == "code"), \
        f"{name} is committed with outputs: strip them"
    monkeypatch.setenv("HANDDB_DB", str(demo_db))
    NotebookClient(book, timeout=CELL_TIMEOUT_S, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [output for cell in book.cells if cell.cell_type == "code"
               for output in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    assert any("image/png" in o.get("data", {}) for o in outputs), "no figure drawn"
