"""The real tool files that ingest build into clips, without Prefect; the refused ones are
recorded and the rest of the inbox is built (issue 15)."""

import pytest

from handdb.build import BuildOptions, build_in_process
from handdb.store.query import query
from tests.support.real_tools import tool_inbox


@pytest.fixture(scope="module")
def built(real_tools, dhg_sample, tmp_path_factory):
    root = tmp_path_factory.mktemp("real-tools")
    inbox = tool_inbox(real_tools, dhg_sample, root / "inbox")
    db = str(root / "db")
    return build_in_process(inbox, db, BuildOptions(export_usd=False)), db


def test_real_files_build_into_clips(built):
    summary, db = built
    assert summary.ok
    assert sorted(summary.processed) == ["brice-right", "dhg", "ih-cap3", "mp-hand0", "signer"]
    rows = query(db, "SELECT clip_id, n_frames, source_format FROM clips ORDER BY clip_id")
    assert rows.to_pylist() == [
        {"clip_id": "brice-right", "n_frames": 20, "source_format": "dlc"},
        {"clip_id": "dhg", "n_frames": 95, "source_format": "dhg"},
        {"clip_id": "ih-cap3", "n_frames": 1, "source_format": "interhand"},
        {"clip_id": "mp-hand0", "n_frames": 64, "source_format": "mediapipe_csv"},
        {"clip_id": "signer", "n_frames": 9, "source_format": "openpose"},
    ]


def test_refused_real_files_say_what_to_do(built):
    summary, db = built
    refused = {r.file.rsplit("/", 1)[-1]: r for r in summary.refusals}
    assert sorted(refused) == ["glove.clip.json", "kistler.c3d", "opto.c3d"]
    assert refused["kistler.c3d"].field == "POINT:USED"
    assert "export the markers" in refused["kistler.c3d"].reason
    assert refused["opto.c3d"].field == "POINT:FRAMES"
    assert "truncated; export it again" in refused["opto.c3d"].reason
    stored = query(db, "SELECT count(*) AS n FROM quarantine").column("n")[0].as_py()
    assert stored == 3



def test_real_3d_captures_are_fitted_on_their_own_skeleton(built):
    _, db = built
    rows = query(db, "SELECT clip_id, count(DISTINCT joint) AS joints, "
                     "any_value(lift_method) AS method FROM joints_3d "
                     "WHERE clip_id IN ('dhg', 'ih-cap3') GROUP BY clip_id ORDER BY clip_id")
    assert rows.to_pylist() == [{"clip_id": "dhg", "joints": 22, "method": "marker-fit"},
                                {"clip_id": "ih-cap3", "joints": 21, "method": "marker-fit"}]


def test_a_glove_of_ten_markers_is_refused_with_what_to_do(built):
    summary, _ = built
    (glove,) = [r for r in summary.refusals if r.file.endswith("glove.clip.json")]
    assert "at least 11 of the 21 joints" in glove.reason and "marks 10" in glove.reason
    assert "joint_map" in glove.reason


def test_a_short_detector_clip_gets_an_adult_hand(built):
    # nine OpenPose frames of a low-confidence hand: too few for the images to measure a
    # bone, so the given lengths size the average hand (the clip once got a 222 mm
    # metacarpal)
    _, db = built
    rows = query(db, "SELECT bone, length, source FROM bone_lengths WHERE clip_id = 'signer' "
                     "AND bone IN ('index_mcp', 'middle_pip')").to_pylist()
    lengths = {r["bone"]: r["length"] for r in rows}
    assert 60.0 < lengths["index_mcp"] < 100.0 and 35.0 < lengths["middle_pip"] < 55.0
    assert {r["source"] for r in rows} == {"proportions"}


def test_real_hands_keep_their_joint_order(built):
    # the joint-order check (knuckles across the palm, the thumb beside the index) must not
    # flag what real tools and captures give
    _, db = built
    rows = query(db, "SELECT clip_id, flag_reasons FROM clips ORDER BY clip_id").to_pylist()
    assert len(rows) == 5
    for row in rows:
        assert not [r for r in row["flag_reasons"] if "across the palm" in r
                    or "thumb is on" in r], row
