"""The real tool files that ingest build into clips, without Prefect; the refused ones are
recorded and the rest of the inbox is built (issue 15)."""

import pytest

from handdb.build import BuildOptions, build_in_process
from handdb.store.query import query
from tests.unit.ingest.test_real_tools import BRICE_MAP, SIDECAR_2D, SIDECAR_3D, put

BONES = {"bone_lengths": {"index_pip": 40.0, "thumb_cmc": 34.0}}


@pytest.fixture(scope="module")
def built(real_tools, tmp_path_factory):
    root = tmp_path_factory.mktemp("real-tools")
    inbox = root / "inbox"
    put(real_tools, inbox, "openpose", SIDECAR_2D | BONES | {"person": 0, "fps": 25},
        clip_id="signer")
    put(real_tools, inbox, "dlc", SIDECAR_2D | BONES | {
        "individual": "rightHand", "frame_from": "row", "joint_map": BRICE_MAP,
        "image": {"width": 852, "height": 480}}, clip_id="brice-right")
    put(real_tools, inbox, "mediapipe", SIDECAR_2D | BONES | {
        "hand_index": 0, "image": {"width": 1280, "height": 720}}, clip_id="mp-hand0")
    put(real_tools, inbox, "interhand", SIDECAR_3D | {"capture": "3", "frame_offset": "first"},
        clip_id="ih-cap3")
    put(real_tools, inbox, "kistler", SIDECAR_3D | {"fps": 60}, clip_id="kistler")
    put(real_tools, inbox, "optotrak", SIDECAR_3D | {"joint_map": {"*": None,
                                                                  "Marker_1": "wrist"}},
        clip_id="opto")
    db = str(root / "db")
    return build_in_process(inbox, db, BuildOptions(export_usd=False)), db


def test_real_files_build_into_clips(built):
    summary, db = built
    assert summary.ok
    assert sorted(summary.processed) == ["brice-right", "ih-cap3", "mp-hand0", "signer"]
    rows = query(db, "SELECT clip_id, n_frames, source_format FROM clips ORDER BY clip_id")
    assert rows.to_pylist() == [
        {"clip_id": "brice-right", "n_frames": 20, "source_format": "dlc"},
        {"clip_id": "ih-cap3", "n_frames": 1, "source_format": "interhand"},
        {"clip_id": "mp-hand0", "n_frames": 64, "source_format": "mediapipe_csv"},
        {"clip_id": "signer", "n_frames": 9, "source_format": "openpose"},
    ]


def test_refused_real_files_say_what_to_do(built):
    summary, db = built
    refused = {r.file.rsplit("/", 1)[-1]: r for r in summary.refusals}
    assert sorted(refused) == ["kistler.c3d", "opto.c3d"]
    assert refused["kistler.c3d"].field == "POINT:USED"
    assert "export the markers" in refused["kistler.c3d"].reason
    assert refused["opto.c3d"].field == "POINT:FRAMES"
    assert "truncated; export it again" in refused["opto.c3d"].reason
    stored = query(db, "SELECT count(*) AS n FROM quarantine").column("n")[0].as_py()
    assert stored == 2
