"""What ``handdb build`` prints as it runs, run as a user would, off a terminal."""

import os
import re
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from handdb.cli import EXIT_QUARANTINED, app

#: The reason the broken sidecar below is refused with.
REASON = "field 'hand': is required"


@pytest.fixture
def inbox_with_a_refusal(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=1)
    write_clip(inbox, "bad", seed=2)
    (inbox / "bad.clip.json").write_text('{"skeleton": "mediapipe21", "fps": 30}')
    return inbox


def timing(output: str) -> tuple[float, float]:
    """The summary's wall time and the part of it spent on the clips, seconds."""
    found = re.search(r" in ([\d.]+) s \(([\d.]+) s planning and processing clips\)", output)
    assert found, output
    return float(found.group(1)), float(found.group(2))


def test_off_a_terminal_each_event_is_one_plain_line(inbox_with_a_refusal, tmp_path):
    result = CliRunner().invoke(app, ["build", "--inbox", str(inbox_with_a_refusal),
                                      "--db", str(tmp_path / "db"), "--no-usd",
                                      "--runner", "local"])
    assert result.exit_code == EXIT_QUARANTINED, result.output
    output = result.output
    assert "\x1b" not in output and "\r" not in output
    lines = [re.sub(r"^\s*[\d.]+ s  ", "", line) for line in output.splitlines()]
    assert "alpha: lifting to 3D" in lines and "alpha: storing its tables" in lines
    assert any(line.startswith("alpha: done (") for line in lines)
    assert output.count(REASON) == 1
    total, work = timing(output)
    # a short clip on warm stages takes under the 0.1 s the summary shows
    assert total >= work >= 0


@pytest.mark.slow
def test_a_prefect_build_prints_a_refusal_once_and_its_wall_time(inbox_with_a_refusal,
                                                                  tmp_path):
    env = {**os.environ, "COLUMNS": "200"}
    started = subprocess.run(
        [sys.executable, "-c", "from handdb.cli import main; main()", "build",
         "--inbox", str(inbox_with_a_refusal), "--db", str(tmp_path / "db"), "--no-usd"],
        capture_output=True, text=True, env=env)
    output = started.stdout + started.stderr
    assert started.returncode == EXIT_QUARANTINED, output
    assert output.count(REASON) == 1, output
    total, work = timing(output)
    # The wall time holds Prefect's temporary server starting and stopping.
    assert total > work


CHECK_PROBE = """
import sys
from handdb.cli import main
sys.argv = ["handdb", "build", "--inbox", {inbox!r}, "--db", {db!r}, {option!r}, "bogus"]
try:
    main()
except SystemExit as exit:
    print("STATUS:", exit.code)
print("LOADED:", ",".join(m for m in ("handdb.build.stages", "numba", "prefect")
                          if m in sys.modules))
"""


@pytest.mark.parametrize("option, kind", [("--lift", "lifting method"),
                                          ("--gap-fill", "gap-filling method"),
                                          ("--runner", "runner")])
def test_a_mistyped_name_is_refused_before_the_stages_load(tmp_path, option, kind):
    (tmp_path / "inbox").mkdir()
    code = CHECK_PROBE.format(inbox=str(tmp_path / "inbox"), db=str(tmp_path / "db"),
                              option=option)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert f"unknown {kind} 'bogus'; known: " in done.stderr
    assert "STATUS: 1" in done.stdout and "LOADED: \n" in done.stdout
    assert not (tmp_path / "db").exists()
