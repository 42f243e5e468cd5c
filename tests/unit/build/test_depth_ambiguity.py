"""A clip whose depth pose is as likely its mirror image is stored so, and said so."""

import json
import math

import numpy as np
import pytest

from handdb import validation
from handdb.build import (
    BuildContext,
    BuildOptions,
    build_in_process,
    plan_build,
    run_clip,
    summary_markdown,
)
from handdb.build.describe import clip_line
from handdb.cli import print_summary
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import get_format
from handdb.lifting.kinematic import MIRROR_SETTLED_ODDS
from handdb.store import query
from handdb.synthetic import synthesize_clip

#: A clean synthetic clip whose chirality only the palm's arch tells, weakly (see
#: ``WEAK_CHIRALITY`` in ``tests/unit/lifting/test_real_hands.py``): its mirror is not
#: settled though the pose chosen is right.
UNSURE_MOTION, UNSURE_SEED, UNSURE_FRAMES = "random", 0, 100

COLUMNS = ("SELECT clip_id, lift_method, depth_log_odds, depth_ambiguous, lift_note, flagged "
           "FROM clips ORDER BY clip_id")


def write_tracks(inbox, clip_id, clip):
    skeleton = load_skeleton(clip.skeleton)
    (inbox / f"{clip_id}.clip.json").write_text(json.dumps(clip.sidecar()))
    fmt = get_format("tracks_csv")
    fmt.write(inbox / f"{clip_id}{fmt.suffix}", clip.uv, np.full(clip.uv.shape[:2], 0.9),
              skeleton)


def write_markers(inbox, clip_id, clip):
    skeleton = load_skeleton(clip.skeleton)
    (inbox / f"{clip_id}.clip.json").write_text(json.dumps(
        {"skeleton": clip.skeleton, "hand": clip.hand, "fps": clip.fps, "subject": "s9",
         "units": clip.units}))
    fmt = get_format("markers_csv")
    fmt.write(inbox / f"{clip_id}{fmt.suffix}", clip.xyz, skeleton)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """An inbox of an unsure 2D clip, a settled one and a marker clip, and its database."""
    root = tmp_path_factory.mktemp("depth")
    inbox = root / "inbox"
    inbox.mkdir()
    write_tracks(inbox, "unsure", synthesize_clip(UNSURE_MOTION, UNSURE_FRAMES,
                                                  camera="orthographic", seed=UNSURE_SEED))
    write_tracks(inbox, "settled", synthesize_clip("clench", 60, seed=1))
    write_markers(inbox, "markers", synthesize_clip("wave", 12, seed=5))
    db = str(root / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["markers", "settled", "unsure"]
    return inbox, db, summary


def test_the_depth_pose_s_odds_are_stored_for_every_lifted_clip(built):
    _, db, _ = built
    rows = {r["clip_id"]: r for r in query(db, COLUMNS).to_pylist()}
    unsure, settled, markers = rows["unsure"], rows["settled"], rows["markers"]
    assert unsure["depth_ambiguous"] is True
    assert unsure["depth_log_odds"] < math.log(MIRROR_SETTLED_ODDS)
    assert "mirror not settled" in unsure["lift_note"]
    assert settled["depth_ambiguous"] is False
    assert settled["depth_log_odds"] >= math.log(MIRROR_SETTLED_ODDS)
    assert settled["lift_note"] is None
    assert markers["lift_method"] == "marker-fit"
    assert markers["depth_log_odds"] is None and markers["depth_ambiguous"] is None
    # a coin-flip depth is still a pose a hand can take: not flagged for it
    assert not unsure["flagged"]


def test_the_summary_names_the_ambiguous_clip_with_the_lifting_s_words(built):
    _, db, summary = built
    assert list(summary.depth_ambiguous) == ["unsure"]
    note = summary.depth_ambiguous["unsure"]
    assert "times as likely as all of them flipped" in note
    assert f"| unsure | {note} |" in summary_markdown(summary)
    assert "- depth ambiguous (the mirror image as likely): 1" in summary_markdown(summary)


def test_the_command_line_warns_of_the_ambiguous_clip(built, capsys):
    _, _, summary = built
    print_summary(summary)
    warnings = [line for line in capsys.readouterr().err.splitlines()
                if "depth ambiguous" in line]
    assert warnings == [f"  depth ambiguous unsure: {summary.depth_ambiguous['unsure']}"]


def test_clip_summary_shows_it(built):
    _, db, _ = built
    rows = query(db, "SELECT clip_id FROM clip_summary WHERE depth_ambiguous").to_pylist()
    assert rows == [{"clip_id": "unsure"}]


def test_a_rebuild_that_reads_the_lift_back_keeps_its_odds(built, monkeypatch):
    inbox, db, _ = built
    before = query(db, COLUMNS).to_pylist()
    monkeypatch.setattr(validation, "VERSION", validation.VERSION + 1)
    options = BuildOptions(export_usd=False)
    plan = plan_build(inbox, db, options)
    assert {c.start for c in plan.clips} == {"validate"}
    context = BuildContext(inbox=str(inbox), db=db, options=options, ratios=plan.xray.ratios)
    lines = {item.clip_id: clip_line(item, run_clip(item, context)) for item in plan.todo}
    assert query(db, COLUMNS).to_pylist() == before
    assert "; depth ambiguous: clip-wide mirror not settled" in lines["unsure"]
    assert "depth ambiguous" not in lines["settled"] + lines["markers"]
