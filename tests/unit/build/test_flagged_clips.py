"""A clip no hand could produce is stored, flagged with its reasons, and said so."""

import json

from handdb.build import BuildOptions, build_in_process, summary_markdown
from handdb.store import query


def test_an_implausible_clip_is_stored_flagged_and_reported(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "fine", seed=1)
    write_clip(inbox, "giant", seed=2)
    sidecar = inbox / "giant.clip.json"
    doc = json.loads(sidecar.read_text())
    doc["bone_lengths"] = {bone: 3.0 * length for bone, length in doc["bone_lengths"].items()}
    sidecar.write_text(json.dumps(doc))
    db = str(tmp_path / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["fine", "giant"]
    assert list(summary.flagged) == ["giant"]
    assert "outside the" in summary.flagged["giant"][0]
    assert "| giant |" in summary_markdown(summary)
    rows = query(db, "SELECT clip_id, flagged, len(flag_reasons) AS n FROM clips "
                     "ORDER BY clip_id").to_pylist()
    assert [(r["clip_id"], r["flagged"], r["n"] > 0) for r in rows] == [
        ("fine", False, False), ("giant", True, True)]
    flagged = query(db, "SELECT clip_id, count(*) AS n FROM joints_3d WHERE flagged "
                        "GROUP BY clip_id").to_pylist()
    assert [r["clip_id"] for r in flagged] == ["giant"]
