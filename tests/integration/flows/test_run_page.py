"""What a build's run page in Prefect says, read back through the Prefect client.

Each clip's INFO line reaches the API while the terminal shows none; the run is named by
what it did and ends in a state that says so; the ``runs`` row links the flow run; a build
with nothing to do leaves the database's latest summary artifact standing; the served
deployment describes itself in markdown.
"""

import os
import re
import subprocess
import sys
import uuid
from logging import ERROR, INFO

import pytest
from handdb_flows.build import DESCRIPTION, build, summary_key
from handdb_flows.serve import deployment_settings
from handdb_flows.settings import quick_flows, shared_api
from prefect.client.orchestration import get_client
from prefect.client.schemas.filters import (
    ArtifactFilter,
    ArtifactFilterFlowRunId,
    ArtifactFilterKey,
    LogFilter,
    LogFilterFlowRunId,
)
from prefect.client.schemas.objects import StateType
from prefect.logging.handlers import APILogHandler

from handdb.cli import EXIT_QUARANTINED
from handdb.store.query import query
from tests.support.paths import REPO

#: Seconds a command-line build may take here, server start-up included.
BUILD_TIMEOUT_S = 600


def spoil_value(track, row: int = 5) -> None:
    """Make the ``u`` of data row ``row`` of a tracks CSV unreadable ("abc")."""
    lines = track.read_text().splitlines()
    frame, joint, _, v, conf = lines[row].split(",")
    lines[row] = ",".join([frame, joint, "abc", v, conf])
    track.write_text("\n".join(lines) + "\n")


def flow_run_logs(client, flow_run_id) -> list:
    """Every log of the flow run ``flow_run_id`` the server holds, oldest first."""
    return client.read_logs(log_filter=LogFilter(flow_run_id=LogFilterFlowRunId(
        any_=[flow_run_id])))


def runs_rows(db) -> list[dict]:
    return query(str(db), "SELECT * FROM runs ORDER BY started_at").to_pylist()


def test_a_command_line_build_logs_each_clip_to_the_server_and_nothing_to_the_terminal(
        tmp_path, write_clip):
    inbox, db = tmp_path / "inbox", tmp_path / "db"
    inbox.mkdir()
    write_clip(inbox, "alpha", seed=1)
    spoil_value(write_clip(inbox, "bravo", seed=2))
    # the user's environment: Prefect's logging as handdb's flows set it, a server of their own
    env = {k: v for k, v in os.environ.items() if not k.startswith("PREFECT_LOGGING_")}
    with shared_api() as api_url:
        env["PREFECT_API_URL"] = api_url
        result = subprocess.run(
            [sys.executable, "-c", "from handdb.cli import main; main()", "build",
             "--inbox", str(inbox), "--db", str(db), "--no-usd", "--workers", "2"],
            cwd=REPO, env=env, capture_output=True, text=True, timeout=BUILD_TIMEOUT_S)
        terminal = result.stdout + result.stderr
        assert result.returncode == EXIT_QUARANTINED, terminal

        (row,) = runs_rows(db)
        flow_run_id = uuid.UUID(row["flow_run_id"])
        assert row["flow_run_url"] == f"{api_url.removesuffix('/api')}/flow-runs/flow-run/" \
                                      f"{flow_run_id}"
        assert f"Prefect run: {row['flow_run_url']}" in terminal
        with get_client(sync_client=True) as client:
            flow_run = client.read_flow_run(flow_run_id)
            logs = flow_run_logs(client, flow_run_id)

    assert flow_run.name == "build 2 clips (1 processed, 1 refused)"
    assert flow_run.state.type == StateType.COMPLETED
    assert flow_run.state.name == "Completed with refusals"
    assert flow_run.state.message == ("1 input refused (see the quarantine table); "
                                      "1 of 2 clips processed, 0 unchanged")
    clip_lines = [log.message for log in logs
                  if log.level == INFO and log.message.startswith("clip ")]
    assert len(clip_lines) == 2, [log.message for log in logs]
    done = next(line for line in clip_lines if line.startswith("clip alpha"))
    assert done == ("clip alpha: ran ingest, lengths, gap_fill, lift, validate, export, "
                    "commit; 40 frames")
    refused = next(line for line in clip_lines if line.startswith("clip bravo"))
    assert re.fullmatch(r"clip bravo refused: \S+/bravo\.tracks\.csv:6: field 'u': 'abc' is not "
                        r"a number", refused), refused
    for line in clip_lines:
        assert line not in terminal
    assert "clip alpha" not in terminal and "INFO" not in terminal


def test_a_build_that_fails_a_clip_ends_failed_and_says_which(inbox, tmp_path):
    db = tmp_path / "db"
    (db / "reports").mkdir(parents=True)
    (db / "reports" / "bravo").write_text("a file where bravo's report folder belongs")
    from tests.support.building import run

    with quick_flows():
        summary = run(str(inbox), str(db), workers=2)
    assert list(summary.failed) == ["bravo"] and summary.flow_run_id is not None
    (row,) = runs_rows(db)
    assert (row["status"], row["flow_run_id"]) == ("failed", summary.flow_run_id)
    # the temporary server of a single build stops with it: no link that leads nowhere
    assert row["flow_run_url"] is None and summary.flow_run_url is None

    APILogHandler().flush()
    with get_client(sync_client=True) as client:
        flow_run = client.read_flow_run(uuid.UUID(summary.flow_run_id))
        logs = flow_run_logs(client, flow_run.id)
    assert flow_run.name == "build 3 clips (2 processed, 1 failed)"
    assert (flow_run.state.type, flow_run.state.name) == (StateType.FAILED, "Failed")
    assert flow_run.state.message == "1 of 3 clips failed (bravo); 2 of 3 clips processed, " \
                                     "0 unchanged"
    levels = {log.message: log.level for log in logs}
    failure = next(m for m in levels if m.startswith("clip bravo failed at export: "))
    assert levels[failure] == ERROR and "reports/bravo" in failure
    processed = [m for m in levels if m.startswith(("clip alpha: ran", "clip charlie: ran"))]
    assert len(processed) == 2 and {levels[m] for m in processed} == {INFO}


def test_a_scheduled_build_with_nothing_to_do_keeps_the_latest_summary(inbox, tmp_path):
    db = str(tmp_path / "db")
    # as a deployment runs it: the flow itself, also when there is nothing to do
    with quick_flows():
        first = build(inbox=str(inbox), db=db, export_usd=False, return_state=True)
        second = build(inbox=str(inbox), db=db, export_usd=False, return_state=True)
    assert first.result().changed and not second.result().changed
    assert second.name == "Completed" and second.message == "0 of 3 clips processed, 3 unchanged"

    key = summary_key(db)
    with get_client(sync_client=True) as client:
        versions = client.read_artifacts(
            artifact_filter=ArtifactFilter(key=ArtifactFilterKey(any_=[key])))
        second_run = second.state_details.flow_run_id
        own = client.read_artifacts(artifact_filter=ArtifactFilter(
            flow_run_id=ArtifactFilterFlowRunId(any_=[second_run])))
        renamed = client.read_flow_run(second_run).name
    assert [artifact.flow_run_id for artifact in versions] == [first.state_details.flow_run_id]
    assert "processed 3" in versions[0].data
    (summary,) = own
    assert summary.key is None and "processed 0, unchanged 3" in summary.data
    assert renamed == "build 3 clips (nothing new)"


def test_summary_keys_are_per_database(tmp_path):
    one, other = summary_key(str(tmp_path / "a" / "db")), summary_key(str(tmp_path / "b" / "db"))
    assert one != other and one.startswith("handdb-build-db-")
    assert re.fullmatch(r"[a-z0-9-]+", one)


def test_the_served_deployment_describes_itself_in_markdown(tmp_path):
    settings = deployment_settings(str(tmp_path / "inbox"), str(tmp_path / "db"))
    deployment = build.to_deployment(**settings, interval=60)
    assert deployment.description == DESCRIPTION == build.description
    for markup in ("``", ":class:", ":func:", ":mod:"):
        assert markup not in deployment.description
    assert deployment.parameters["db"] == str(tmp_path / "db")


@pytest.mark.parametrize("name", ["Completed", "Completed with refusals", "Failed"])
def test_every_final_state_is_described(name):
    assert f"*{name}*" in DESCRIPTION
