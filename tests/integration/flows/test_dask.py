"""The per-clip tasks on Dask (prefect-dask): a local cluster gives the thread runner's tables,
and the run's page in Prefect says what the thread runner's says."""

import hashlib
import uuid
from logging import INFO

import pytest
from distributed import LocalCluster
from distributed.diagnostics.plugin import SchedulerPlugin
from handdb_flows.settings import quick_flows, shared_api
from prefect.client.orchestration import get_client
from prefect.client.schemas.filters import ArtifactFilter, ArtifactFilterFlowRunId
from prefect.client.schemas.objects import StateType
from prefect.logging.handlers import APILogHandler

from handdb.store.query import query
from tests.integration.flows.test_run_page import flow_run_logs
from tests.support.building import run

pytestmark = pytest.mark.slow


def file_digests(db):
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*")) if path.is_file() and path.parent.name != "runs"
        and path.name != ".lock"
    }


def test_dask_runner_builds_the_same_database_as_threads(inbox, tmp_path):
    with quick_flows(), shared_api():
        threads = run(str(inbox), str(tmp_path / "threads"), workers=2)
        dask = run(str(inbox), str(tmp_path / "dask"), workers=2, runner="dask")
        APILogHandler().flush()
        with get_client(sync_client=True) as client:
            flow_run = client.read_flow_run(uuid.UUID(dask.flow_run_id))
            logs = flow_run_logs(client, flow_run.id)
            artifacts = client.read_artifacts(artifact_filter=ArtifactFilter(
                flow_run_id=ArtifactFilterFlowRunId(any_=[flow_run.id])))
    assert sorted(dask.processed) == sorted(threads.processed) == ["alpha", "bravo", "charlie"]
    assert file_digests(tmp_path / "dask") == file_digests(tmp_path / "threads")

    assert flow_run.name == "build 3 clips (3 processed)"
    assert (flow_run.state.type, flow_run.state.name) == (StateType.COMPLETED, "Completed")
    assert flow_run.state.message == "3 of 3 clips processed, 0 unchanged"
    clip_lines = sorted(log.message for log in logs
                        if log.level == INFO and log.message.startswith("clip "))
    assert clip_lines == [f"clip {clip_id}: ran ingest, lengths, gap_fill, lift, validate, "
                          "export, commit; 40 frames" for clip_id in ("alpha", "bravo", "charlie")]
    # the tasks ran in the Dask workers' processes, and reported from there
    task_ends = [log for log in logs if log.task_run_id is not None
                 and log.message == "Finished in state Completed()"]
    assert len({log.task_run_id for log in task_ends}) == 3
    by_key = {artifact.key: artifact for artifact in artifacts}
    assert {f"validation-{clip_id}" for clip_id in ("alpha", "bravo", "charlie")} < set(by_key)
    assert all(by_key[f"validation-{clip_id}"].task_run_id is not None
               for clip_id in ("alpha", "bravo", "charlie"))
    (summary,) = [artifact for key, artifact in by_key.items()
                  if key.startswith("handdb-build-")]
    assert "processed 3" in summary.data


class FinishedTasks(SchedulerPlugin):
    """Counts the tasks a Dask scheduler saw finish."""

    def __init__(self) -> None:
        self.count = 0

    def transition(self, key, start, finish, *args, **kwargs) -> None:
        if finish == "memory":
            self.count += 1


def test_dask_runner_joins_an_existing_cluster(inbox, tmp_path):
    finished = FinishedTasks()
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=True,
                      dashboard_address=None) as cluster, quick_flows():
        cluster.scheduler.add_plugin(finished)
        summary = run(str(inbox), str(tmp_path / "db"), workers=2, runner="dask",
                      address=cluster.scheduler_address, export_usd=False)
    assert finished.count >= 3  # one task per clip, each finished on the cluster
    assert summary.ok and sorted(summary.processed) == ["alpha", "bravo", "charlie"]
    assert query(str(tmp_path / "db"), "SELECT count(*) AS n FROM clips").column("n")[0] \
        .as_py() == 3
