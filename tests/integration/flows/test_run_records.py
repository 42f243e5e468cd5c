"""Run records: a ``runs`` row and Prefect markdown artifacts for every build."""

import json

from handdb_flows.build import artifact_key, summary_key
from handdb_flows.settings import quick_flows
from prefect.client.orchestration import get_client
from prefect.client.schemas.filters import ArtifactFilter, ArtifactFilterKey

from handdb import __version__
from handdb.lifting import DEFAULT_METHOD as DEFAULT_LIFT
from handdb.store.query import query
from tests.support.building import run


def markdown_artifacts(key: str) -> list[str]:
    """Every markdown artifact stored under ``key``, as text."""
    with get_client(sync_client=True) as client:
        found = client.read_artifacts(
            artifact_filter=ArtifactFilter(key=ArtifactFilterKey(any_=[key])))
    return [artifact.data for artifact in found if artifact.type == "markdown"]


def test_every_build_leaves_a_runs_row_and_a_summary_artifact(inbox, tmp_path, write_clip,
                                                               n_frames):
    db = tmp_path / "db"
    (inbox / "lost.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")
    with quick_flows():
        first = run(str(inbox), str(db), export_usd=False, workers=2, gap_fill="linear")
        second = run(str(inbox), str(db), export_usd=False, workers=2, gap_fill="linear")

    runs = query(str(db), "SELECT * FROM runs ORDER BY started_at").to_pylist()
    assert [r["run_id"] for r in runs] == [first.run_id, second.run_id]
    assert [(r["n_processed"], r["n_unchanged"], r["n_quarantined"]) for r in runs] == \
        [(3, 0, 1), (0, 3, 1)]
    for row in runs:
        assert row["status"] == "completed" and row["handdb_version"] == __version__
        assert row["finished_at"] >= row["started_at"]
        parameters = json.loads(row["parameters"])
        assert parameters["gap_fill"] == "linear" and parameters["export_usd"] is False
        assert parameters["inbox"] == str(inbox) and parameters["db"] == str(db)
        assert set(json.loads(row["timings"])) == {"scan", "clips"}

    summaries = {text.splitlines()[0]: text for text in markdown_artifacts(summary_key(str(db)))}
    report = summaries[f"# handdb build {first.run_id}"]
    assert "processed 3" in report and f"frames processed: {3 * n_frames}" in report
    assert "lost.tracks.csv" in report
    figures = {line.split(" | ")[0].strip("| ") for line in report.splitlines()
               if line.startswith("| ") and f" | {DEFAULT_LIFT} | " in line}
    assert figures == {"alpha", "bravo", "charlie"}
    # the second build had nothing to do: it ran without Prefect and left no artifact
    assert f"# handdb build {second.run_id}" not in summaries
    assert any("Depth validation: bravo" in text
               for text in markdown_artifacts(artifact_key("validation", "bravo")))
