"""The per-clip tasks on Dask (prefect-dask): a local cluster gives the thread runner's tables."""

import hashlib

import pytest
from distributed import LocalCluster
from distributed.diagnostics.plugin import SchedulerPlugin
from handdb_flows.settings import quick_flows

from handdb.store.query import query
from tests.support.building import run

pytestmark = pytest.mark.slow


def file_digests(db):
    return {
        path.relative_to(db).as_posix(): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(db.rglob("*")) if path.is_file() and path.parent.name != "runs"
        and path.name != ".lock"
    }


def test_dask_runner_builds_the_same_database_as_threads(inbox, tmp_path):
    with quick_flows():
        threads = run(str(inbox), str(tmp_path / "threads"), workers=2)
        dask = run(str(inbox), str(tmp_path / "dask"), workers=2, runner="dask")
    assert sorted(dask.processed) == sorted(threads.processed) == ["alpha", "bravo", "charlie"]
    assert file_digests(tmp_path / "dask") == file_digests(tmp_path / "threads")


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
