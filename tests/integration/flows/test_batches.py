"""One task per batch of small clips: each clip keeps its outcome, artifact and commit."""

from handdb_flows.build import artifact_key, build
from handdb_flows.settings import quick_flows
from prefect.client.orchestration import get_client
from prefect.client.schemas.filters import (
    ArtifactFilter,
    ArtifactFilterFlowRunId,
    FlowRunFilter,
    FlowRunFilterId,
)

from handdb.store.query import query


def test_a_batch_commits_its_clips_each_and_a_failing_clip_fails_alone(inbox, tmp_path):
    db = tmp_path / "db"
    (db / "reports").mkdir(parents=True)
    (db / "reports" / "bravo").write_text("a file where bravo's report folder belongs")
    with quick_flows():
        # one batch in flight: the three small clips are one task
        state = build(inbox=str(inbox), db=str(db), window=1, return_state=True)
    summary = state.result(raise_on_failure=False)
    assert list(summary.failed) == ["bravo"] and sorted(summary.processed) == ["alpha", "charlie"]
    committed = query(str(db), "SELECT clip_id FROM clips ORDER BY clip_id")
    assert committed.column("clip_id").to_pylist() == ["alpha", "charlie"]

    flow_run_id = state.state_details.flow_run_id
    with get_client(sync_client=True) as client:
        (task_run,) = client.read_task_runs(
            flow_run_filter=FlowRunFilter(id=FlowRunFilterId(any_=[flow_run_id])))
        published = client.read_artifacts(artifact_filter=ArtifactFilter(
            flow_run_id=ArtifactFilterFlowRunId(any_=[flow_run_id])))
    artifacts = {clip: [artifact for artifact in published
                        if artifact.key == artifact_key("validation", clip)]
                 for clip in ("alpha", "bravo", "charlie")}
    assert task_run.name == "process alpha (+2)"
    # the I/O failure was retried, and each retry redid bravo alone: one artifact each
    assert task_run.run_count == 3
    assert [len(artifacts[clip]) for clip in ("alpha", "bravo", "charlie")] == [1, 0, 1]
    assert {artifact.task_run_id for artifact in artifacts["alpha"] + artifacts["charlie"]} \
        == {task_run.id}
