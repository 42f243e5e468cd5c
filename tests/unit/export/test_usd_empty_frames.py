"""A real detector clip whose first and last frames saw no point still gets its USD file:
the frames that place every joint are keyed and read back through UsdSkel (issue 14)."""

import json
import shutil

import numpy as np
from pxr import UsdSkel

from handdb.build import BuildOptions, build_in_process
from handdb.export.rotations import CAMERA_TO_Y_UP
from handdb.hand.skeletons import load_skeleton
from handdb.store import query
from tests.support.usd_reading import joint_world_positions, open_skeleton, validation_errors

#: The real OpenPose sample's nine frames, the first and the last emptied.
N_FRAMES, EMPTIED = 9, (0, 8)
SIDECAR = {"skeleton": "mediapipe21", "hand": "left", "fps": 25, "subject": "signer01",
           "units": "mm", "camera": {"model": "orthographic"}, "person": 0}


def test_real_openpose_clip_with_empty_end_frames_exports_its_observed_span(real_tools,
                                                                           tmp_path):
    inbox = tmp_path / "inbox"
    folder = inbox / "signer.openpose"
    shutil.copytree(real_tools / "openpose-hand", folder)
    for frame in EMPTIED:
        path = folder / f"video_0000000000{frame:02d}_keypoints.json"
        path.write_text(json.dumps(json.loads(path.read_text()) | {"people": []}))
    (inbox / "signer.clip.json").write_text(json.dumps(SIDECAR))
    db = tmp_path / "db"
    summary = build_in_process(inbox, str(db), BuildOptions())
    assert list(summary.processed) == ["signer"] and not summary.refusals
    assert any(r.startswith("USD animates frames 1-7") for r in summary.flagged["signer"])
    (row,) = query(str(db), "SELECT usd_path FROM clips").to_pylist()
    assert row["usd_path"] == "usd/signer.usd"

    clip = open_skeleton(db / row["usd_path"])
    assert validation_errors(clip.stage) == []
    assert (clip.stage.GetStartTimeCode(), clip.stage.GetEndTimeCode()) == (1, 7)
    anim = UsdSkel.Animation(clip.stage.GetPrimAtPath("/LeftHand/signer"))
    assert anim.GetRotationsAttr().GetTimeSamples() == list(range(1, 8))
    skeleton = load_skeleton("mediapipe21")
    joints = query(str(db), "SELECT frame, joint_index, x, y, z FROM joints_3d "
                            "ORDER BY frame, joint_index").to_pydict()
    stored = np.column_stack([joints["x"], joints["y"], joints["z"]]).astype(float)
    stored = stored.reshape(N_FRAMES, skeleton.n_joints, 3)
    assert np.isnan(stored[list(EMPTIED), :, 0]).all() and np.isfinite(stored[1:8]).all()
    stage_xyz = joint_world_positions(clip, N_FRAMES)
    camera_xyz = CAMERA_TO_Y_UP.inv().apply(stage_xyz.reshape(-1, 3)).reshape(stage_xyz.shape)
    lengths = np.linalg.norm(np.diff(stored[1:8, skeleton.bones], axis=2), axis=-1)
    assert np.abs(camera_xyz[1:8] - stored[1:8]).max() < 1e-4 * lengths.min()
    np.testing.assert_allclose(camera_xyz[[0, 8]], camera_xyz[[1, 7]], atol=1e-9)
