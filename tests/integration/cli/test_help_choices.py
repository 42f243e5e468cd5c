"""``--help`` lists every option's valid choices, read from the registries themselves."""

import os
import re
import subprocess
import sys

import pytest

from handdb.build.orchestrators import runner_names
from handdb.gapfill import METHODS as GAP_FILLING
from handdb.lifting import METHODS as LIFTING

#: Wide enough that no help line wraps.
COLUMNS = "1000"


def help_text(*argv: str) -> str:
    """``handdb *argv --help`` as a user's shell prints it, in a fresh interpreter."""
    env = {**os.environ, "COLUMNS": COLUMNS, "NO_COLOR": "1", "TERM": "dumb"}
    result = subprocess.run(
        [sys.executable, "-c", "from handdb.cli import main; main()", *argv, "--help"],
        capture_output=True, text=True, check=True, env=env)
    return result.stdout


def listed_choices(text: str, option: str) -> tuple[str, ...]:
    """The names ``one of: a, b, c`` lists on ``option``'s help line."""
    line = next(line for line in text.splitlines() if re.search(rf"\s{option}\s", line))
    found = re.search(r"one of: ([a-z0-9, -]+?)[):(]", line)
    assert found, f"{option} lists no choices: {line}"
    return tuple(name.strip() for name in found.group(1).split(","))


@pytest.mark.parametrize("option, registered", [
    ("--gap-fill", GAP_FILLING.names()),
    ("--lift", LIFTING.names()),
    ("--compare", LIFTING.names()),
    ("--runner", runner_names()),
])
def test_build_help_lists_exactly_the_registered_names(option, registered):
    assert listed_choices(help_text("build"), option) == registered


def test_every_method_is_registered():
    assert {"auto", "pchip", "previous", "intrafinger-rate"} <= set(GAP_FILLING.names())
    assert {"kinematic", "thesis", "model-fit"} <= set(LIFTING.names())
    assert {"thread", "local"} <= set(runner_names())


def test_gapfill_eval_help_lists_every_method():
    text = help_text("gapfill-eval")
    assert all(name in text for name in GAP_FILLING.names())


PROBE = """
import sys
from handdb.cli import main
sys.argv = ["handdb", "build", "--help"]
try:
    main()
except SystemExit:
    pass
from handdb.gapfill import METHODS as G
from handdb.lifting import METHODS as L
G.check("auto"), L.check("kinematic")
print("HEAVY:" + ",".join(m for m in ("numba", "scipy", "scipy.optimize", "numpy")
                         if m in sys.modules))
"""


def test_listing_and_checking_names_imports_no_method():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True,
                         check=True).stdout
    assert out.rpartition("HEAVY:")[2].strip() == ""
