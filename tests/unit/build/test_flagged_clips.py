"""A clip no hand could produce is stored, flagged with its reasons, and said so."""

import json

from handdb.build import BuildOptions, build_in_process, summary_markdown
from handdb.store import query
from tests.support.building import GIANT_FACTOR, scale_bones


def test_an_implausible_clip_is_stored_flagged_and_reported(tmp_path, write_clip):
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    write_clip(inbox, "fine", seed=1)
    write_clip(inbox, "giant", seed=2)
    scale_bones(inbox, "giant", GIANT_FACTOR)
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


def test_a_joint_map_that_swaps_two_fingers_is_flagged_naming_them(tmp_path):
    # the tool's names are the fingers' own, but the sidecar maps index to ring and back:
    # every bone and angle stays a hand's, only the order across the palm gives it away
    from handdb.hand.skeletons import load_skeleton
    from handdb.ingest import dlc
    from handdb.synthetic import synthesize_clip

    inbox = tmp_path / "inbox"
    inbox.mkdir()
    clip = synthesize_clip("wave", 60, seed=3)
    skeleton = load_skeleton(clip.skeleton)
    dlc.write(inbox / "swapped.dlc.csv", clip.uv, None, skeleton)
    swap = {f"{a}_{part}": f"{b}_{part}" for a, b in (("index", "ring"), ("ring", "index"))
            for part in ("mcp", "pip", "dip", "tip")}
    (inbox / "swapped.clip.json").write_text(json.dumps(clip.sidecar() | {"joint_map": swap}))
    dlc.write(inbox / "fine.dlc.csv", clip.uv, None, skeleton)
    (inbox / "fine.clip.json").write_text(json.dumps(clip.sidecar()))
    db = str(tmp_path / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["fine", "swapped"]
    assert list(summary.flagged) == ["swapped"]
    (reason,) = [r for r in summary.flagged["swapped"] if "across the palm" in r]
    assert "ring_mcp, index_mcp look swapped: check the joint_map" in reason
    rows = query(db, "SELECT joint, count(*) AS n FROM joints_3d WHERE flagged AND "
                     "clip_id = 'swapped' GROUP BY joint ORDER BY joint").to_pylist()
    assert {r["joint"] for r in rows} >= {"index_mcp", "ring_mcp"}
