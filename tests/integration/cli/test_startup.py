"""The command line starts without the heavy dependencies its light commands never use."""

import subprocess
import sys

import pytest
from typer.testing import CliRunner

from handdb.build import BuildOptions, build_in_process
from handdb.cli import LAZY_COMMANDS, app, load_command
from handdb.store.database import Store
from tests.support.store_rows import truth_rows

#: Modules ``handdb --help`` and ``handdb sql`` must not import (each costs 0.2-1 s).
HEAVY = ("pxr", "scipy", "matplotlib", "prefect", "numba", "handdb.lifting",
         "handdb.export", "handdb.synthetic")
#: The lifting package's name table, which every command imports to list the methods.
LIGHT = {"handdb.lifting", "handdb.lifting.methods"}
#: Light modules of a build with nothing to do: the export package's name table (the plan
#: reads the export stage's version) and the lift's result type (the run's summary).
NOOP_BUILD_LIGHT = {"handdb.export", "handdb.export.formats", "handdb.lifting.result"}

PROBE = """
import sys
from handdb.cli import main
sys.argv = ["handdb", *{argv!r}]
try:
    main()
except SystemExit:
    pass
print("IMPORTED:" + "|".join(sorted(m for m in sys.modules if m.split(".")[0] in {roots!r}
                      or m.startswith(("handdb.lifting", "handdb.export", "handdb.synthetic")))))
"""


def imported_by(argv: list[str]) -> set[str]:
    """The heavy modules a fresh interpreter holds after running ``handdb *argv``."""
    roots = {name.split(".")[0] for name in HEAVY if "." not in name}
    result = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, roots=roots)],
                            capture_output=True, text=True, check=True)
    listed = result.stdout.rpartition("IMPORTED:")[2].strip()
    return {name for name in listed.split("|") if name} - LIGHT


@pytest.mark.parametrize("argv", [["--help"], ["sql", "--help"], ["build", "--help"]])
def test_light_commands_do_not_import_the_heavy_libraries(argv):
    assert imported_by(argv) == set()


def test_a_rebuild_with_nothing_to_do_loads_no_stage(tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", tmp_path / "db"
    inbox.mkdir()
    write_clip(inbox, "solo", seed=0)
    assert build_in_process(inbox, str(db), BuildOptions(export_usd=False)).processed == ["solo"]
    argv = ["build", "--inbox", str(inbox), "--db", str(db), "--no-usd"]
    assert imported_by(argv) - NOOP_BUILD_LIGHT == set()


def test_a_lazy_command_imports_its_module_when_it_runs():
    assert "handdb.lifting.registry" in imported_by(["lift", "--help"])


@pytest.mark.parametrize("name", list(LAZY_COMMANDS))
def test_the_listed_help_is_the_commands_own(name):
    command = load_command(name)
    assert command.name == name
    first_line = (command.help or "").strip().splitlines()[0]
    assert first_line == LAZY_COMMANDS[name][2]


def test_every_lazy_command_is_listed_and_runs_its_own_help():
    runner = CliRunner()
    listing = runner.invoke(app, ["--help"])
    assert listing.exit_code == 0
    for name in LAZY_COMMANDS:
        assert name in listing.output
        result = runner.invoke(app, [name, "--help"])
        assert result.exit_code == 0, result.output
        assert f"handdb {name}" in result.output


#: Scans a table in a fresh interpreter; prints the rows, then the modules of ``SLOW_TO_LOAD``
#: it holds.
SCAN_PROBE = """
import sys
from handdb.store.query import query
print(query({db!r}, "SELECT count(*) AS n FROM truth_3d").to_pylist(),
      sorted(m for m in sys.modules if m in {slow!r}))
"""
#: ``pyarrow.dataset`` imports pandas: together 0.3-0.5 s of ``handdb sql``'s start.
SLOW_TO_LOAD = ("pandas", "pyarrow.dataset")


def test_a_query_scans_a_table_without_pyarrow_dataset_or_pandas(tmp_path):
    Store(str(tmp_path / "db")).write("truth_3d", "a", truth_rows("a", 3))
    result = subprocess.run(
        [sys.executable, "-c", SCAN_PROBE.format(db=str(tmp_path / "db"), slow=SLOW_TO_LOAD)],
        capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[{'n': 3}] []"
