"""Marker clips (3D markers, no camera) through the build: fit, calibration, tables, USD."""

import json

import numpy as np
import pytest
from handdb_flows.settings import quick_flows

from handdb.export.rotations import CAMERA_TO_Y_UP
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import get_format
from handdb.store.query import query
from handdb.synthetic import synthesize_clip
from tests.support.building import run
from tests.support.usd_reading import joint_world_positions, open_skeleton

N_FRAMES = 12


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A database built from one marker clip (CSV) and one C3D clip, with truth."""
    root = tmp_path_factory.mktemp("markers")
    inbox = root / "inbox"
    inbox.mkdir()
    skeleton = load_skeleton("mediapipe21")
    rng = np.random.default_rng(5)
    truth = {}
    for clip_id, fmt in [("mk-csv", "markers_csv"), ("mk-c3d", "c3d")]:
        clip = synthesize_clip("wave", N_FRAMES, seed=5)
        markers = clip.xyz + rng.normal(0.0, 0.5, clip.xyz.shape)
        markers[rng.random(markers.shape[:2]) < 0.2] = np.nan
        (inbox / f"{clip_id}.clip.json").write_text(json.dumps(
            {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s9",
             "units": "mm"}))
        rate = {"point_rate": 30.0} if fmt == "c3d" else {}
        get_format(fmt).write(inbox / f"{clip_id}{get_format(fmt).suffix}", markers, skeleton,
                              **rate)
        get_format("truth_csv").write(inbox / f"{clip_id}.truth.csv", clip.xyz, skeleton)
        truth[clip_id] = clip.xyz
    db = root / "db"
    with quick_flows():
        summary = run(str(inbox), str(db), workers=2)
    return summary, db, truth


def test_marker_clips_are_fitted_and_calibrated(built):
    summary, db, _ = built
    assert summary.ok and sorted(summary.processed) == ["mk-c3d", "mk-csv"]
    clips = query(str(db), "SELECT clip_id, camera_model, lift_method, source_format "
                           "FROM clips ORDER BY clip_id").to_pylist()
    assert [c["camera_model"] for c in clips] == ["none", "none"]
    assert {c["lift_method"] for c in clips} == {"marker-fit"}
    assert [c["source_format"] for c in clips] == ["c3d", "markers_csv"]
    sources = query(str(db), "SELECT DISTINCT source FROM bone_lengths").column(0).to_pylist()
    assert sources == ["calibrated"]
    angles = query(str(db), "SELECT count(DISTINCT frame) AS frames, count(DISTINCT axis) AS "
                            "axes FROM joint_angles WHERE clip_id = 'mk-csv'").to_pylist()[0]
    assert angles["frames"] == N_FRAMES and angles["axes"] >= 3
    seen = query(str(db), "SELECT count(*) AS n FROM markers_3d WHERE clip_id = 'mk-csv'")
    assert 0.6 * N_FRAMES * 21 < seen.column("n")[0].as_py() < N_FRAMES * 21


def test_fit_is_validated_against_truth(built):
    _, db, truth = built
    rows = query(str(db), "SELECT clip_id, method, avg(mpjpe) AS mpjpe FROM validation_joint "
                          "GROUP BY ALL").to_pylist()
    assert {r["method"] for r in rows} == {"marker-fit"}
    for row in rows:
        assert row["mpjpe"] < 5.0
    lifted = query(str(db), "SELECT x, y, z FROM joints_3d WHERE clip_id = 'mk-csv' "
                            "ORDER BY frame, joint_index")
    xyz = np.stack([lifted.column(c).to_numpy() for c in "xyz"], axis=-1).reshape(N_FRAMES, 21, 3)
    error = np.linalg.norm(xyz - truth["mk-csv"], axis=-1).mean()
    assert error < 5.0


def test_usd_uses_the_fitted_rotations_and_reproduces_the_joints(built):
    _, db, _ = built
    lifted = query(str(db), "SELECT x, y, z FROM joints_3d WHERE clip_id = 'mk-csv' "
                            "ORDER BY frame, joint_index")
    xyz = np.stack([lifted.column(c).to_numpy() for c in "xyz"], axis=-1).reshape(N_FRAMES, 21, 3)
    stage_xyz = joint_world_positions(open_skeleton(db / "usd" / "mk-csv.usd"), N_FRAMES)
    camera_xyz = CAMERA_TO_Y_UP.inv().apply(stage_xyz.reshape(-1, 3)).reshape(stage_xyz.shape)
    lengths = query(str(db), "SELECT min(length) AS m FROM bone_lengths WHERE clip_id = 'mk-csv'")
    assert np.abs(camera_xyz - xyz).max() < 1e-4 * lengths.column("m")[0].as_py()
