import json

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import mediapipe, mediapipe_csv, mediapipe_world
from tests.unit.ingest.conftest import hand_track
from tests.unit.ingest.test_markers_csv import SKELETON, marker_spec

IMAGE = {"width": 640, "height": 480}


def long_csv(hands=(0, 1), frames=(0, 1), extra=""):
    rows = ["frame,hand,landmark,x,y,z" + extra]
    for frame in frames:
        for hand in hands:
            rows += [f"{frame},{hand},{k},{0.2 + 0.5 * hand + 0.01 * k},{0.5 + 0.01 * frame},0.0"
                     for k in range(21)]
    return "\n".join(rows) + "\n"


def read_csv(tmp_path, spec_for, skeleton, text, **sidecar):
    path = tmp_path / "clip.mediapipe.csv"
    path.write_text(text)
    return mediapipe_csv.read(path, spec_for(tmp_path, **({"image": IMAGE} | sidecar)), skeleton)


@pytest.mark.parametrize("hand_index", [0, 1])
def test_long_csv_picks_a_hand_by_index(tmp_path, spec_for, mediapipe21, hand_index):
    obs = read_csv(tmp_path, spec_for, mediapipe21, long_csv(), hand_index=hand_index)
    assert obs.n_frames == 2 and obs.n_rows == 42
    np.testing.assert_allclose(obs.u[obs.joint == 0], (0.2 + 0.5 * hand_index) * 640)
    assert np.isnan(obs.confidence).all()
    assert obs.line[0] == 2 + 21 * hand_index


def test_names_visibility_and_handedness(tmp_path, spec_for, mediapipe21):
    text = "frame,handedness,landmark,x,y,visibility\n0,Left,WRIST,0.5,0.5,0.0\n" \
           "0,Right,WRIST,0.25,0.5,0.0\n0,Right,pinky_tip,0.3,0.5,0.0\n"
    obs = read_csv(tmp_path, spec_for, mediapipe21, text, handedness="Right")
    np.testing.assert_array_equal(obs.joint, [0, mediapipe21.index("little_tip")])
    np.testing.assert_allclose(obs.u, [160.0, 192.0])
    assert np.isnan(obs.confidence).all(), "all-zero visibility is no confidence"


@pytest.mark.parametrize(("text", "sidecar", "file", "line", "field", "message"), [
    (long_csv(), {}, "clip.mediapipe.csv", 23, "hand", "holds hands 0 and 1"),
    (long_csv(hands=(0,)), {"hand_index": 2}, "clip.clip.json", None, "hand_index",
     "no row of clip.mediapipe.csv has that hand"),
    (long_csv().replace("0,0,4,", "0,0,FOO,", 1), {"hand_index": 0}, "clip.mediapipe.csv", 6,
     "landmark", "'FOO' is not a MediaPipe hand landmark"),
    (long_csv(hands=(0,)).replace("0,0,0,0.2,", "0,0,0,2.2,", 1), {}, "clip.mediapipe.csv", 2,
     "x", "lies far outside the image.*pixels"),
    (long_csv(hands=(0,), extra=",visibility").replace(",0.0\n", ",0.0,3.2\n"), {},
     "clip.mediapipe.csv", 2, "visibility", "a logit"),
    (long_csv(hands=(0,)), {"handedness": "Left"}, "clip.clip.json", None, "handedness",
     "has no 'handedness' column"),
])
def test_long_csv_refusals(tmp_path, spec_for, mediapipe21, text, sidecar, file, line, field,
                           message):
    with pytest.raises(InputError, match=message) as info:
        read_csv(tmp_path, spec_for, mediapipe21, text, **sidecar)
    error = info.value
    assert (error.file.rsplit("/", 1)[-1], error.line, error.field) == (file, line, field)


def tasks_entry(frame, hands):
    """A MediaPipe Tasks HandLandmarkerResult as dataclasses.asdict writes it."""
    return {"frame": frame,
            "handedness": [[{"index": k, "score": 0.9 - 0.1 * k, "display_name": label,
                             "category_name": label}] for k, (label, _) in enumerate(hands)],
            "hand_landmarks": [[{"x": x, "y": 0.5, "z": 0.0, "visibility": 0.0, "presence": 0.0}
                                for _ in range(21)] for _, x in hands],
            "hand_world_landmarks": [[{"x": 0.01 * j, "y": 0.02, "z": 0.0} for j in range(21)]
                                     for _ in hands]}


def test_tasks_results_select_by_handedness_and_carry_world_landmarks(tmp_path, spec_for,
                                                                       mediapipe21):
    doc = {"frames": [tasks_entry(0, [("Left", 0.25), ("Right", 0.75)]),
                      tasks_entry(2, [("Right", 0.5)]), {"frame": 3, "hand_landmarks": []}]}
    path = tmp_path / "clip.mediapipe.json"
    path.write_text(json.dumps(doc))
    obs = mediapipe.read(path, spec_for(tmp_path, image=IMAGE, handedness="Right"), mediapipe21)
    assert obs.n_frames == 4
    np.testing.assert_allclose(obs.u[obs.frame == 0], 0.75 * 640)
    np.testing.assert_allclose(obs.confidence[obs.frame == 0], 0.8)
    np.testing.assert_allclose(obs.confidence[obs.frame == 2], 0.9)
    world = tmp_path / "clip.mediapipe-world.json"
    world.write_text(json.dumps(doc))
    positions = mediapipe_world.read(world, marker_spec(handedness="Right"), SKELETON)
    assert positions.n_frames == 4 and sorted(set(positions.frame.tolist())) == [0, 2]
    np.testing.assert_allclose(positions.xyz[positions.joint == 20], [[200.0, 20.0, 0.0]] * 2)


@pytest.mark.parametrize(("doc", "sidecar", "field", "message"), [
    ({"frames": [tasks_entry(0, [("Left", 0.25), ("Right", 0.75)])]}, {},
     "frames[0].hand_landmarks[1]", 'holds 2 hands.*"hand_index": 0 to 1.*"Left", "Right"'),
    ({"frames": [tasks_entry(0, [("Right", 0.25), ("Right", 0.75)])]}, {"handedness": "Right"},
     "frames[0].hand_landmarks[1]", "two hands labelled"),
    ([[{"x": 0.1, "y": 0.2, "z": 0.0}] * 21], {}, "frames", "without frame numbers"),
    ({"frames": [{"frame": 10**20, "landmarks": [[0.5, 0.5, 0.0]] * 21}]}, {},
     "frames[0].frame", "beyond handdb's limit"),
    ({"frames": [{"frame": 0, "landmarks": [{"x": 0.5}] * 21}]}, {}, "frames[0].landmarks[0]",
     "needs 'y'"),
])
def test_json_refusals(tmp_path, spec_for, mediapipe21, doc, sidecar, field, message):
    path = tmp_path / "clip.mediapipe.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=message) as info:
        mediapipe.read(path, spec_for(tmp_path, image=IMAGE, **sidecar), mediapipe21)
    assert info.value.field == field


def test_one_tasks_result_is_one_frame_and_objects_are_landmarks(tmp_path, spec_for,
                                                                  mediapipe21):
    path = tmp_path / "clip.mediapipe.json"
    result = tasks_entry(0, [("Right", 0.5)])
    del result["frame"]
    path.write_text(json.dumps(result))
    obs = mediapipe.read(path, spec_for(tmp_path, image=IMAGE), mediapipe21)
    assert obs.n_frames == 1 and obs.n_rows == 21
    legacy = {"frames": [{"frame": 1, "landmarks": [{"x": 0.5, "y": 0.25, "z": 0.0}] * 21}]}
    path.write_text(json.dumps(legacy))
    obs = mediapipe.read(path, spec_for(tmp_path, image=IMAGE), mediapipe21)
    np.testing.assert_allclose(obs.uv, [[320.0, 120.0]] * 21)


def test_world_landmarks_are_required_for_a_world_clip(tmp_path):
    path = tmp_path / "clip.mediapipe-world.json"
    path.write_text(json.dumps({"frames": [{"frame": 0, "landmarks": [[0.5, 0.5, 0]] * 21}]}))
    with pytest.raises(InputError, match="holds no world landmarks"):
        mediapipe_world.read(path, marker_spec(), SKELETON)


def world_like(mediapipe21, n_frames=6):
    """A moving hand as MediaPipe's world landmarks: metres around the hand's centre."""
    track = hand_track(mediapipe21, n_frames)
    return (track - track.mean(axis=1, keepdims=True)) / 1000.0


def landmark_rows(xy):
    return "frame,landmark,x,y\n" + "".join(
        f"{t},{k},{x:.6f},{y:.6f}\n" for t, frame in enumerate(xy)
        for k, (x, y) in enumerate(frame))


@pytest.mark.parametrize("layout", ["csv", "json"])
def test_world_landmarks_given_as_image_landmarks_are_refused(tmp_path, spec_for, mediapipe21,
                                                              layout):
    world = world_like(mediapipe21)
    if layout == "csv":
        with pytest.raises(InputError, match=r"world landmarks .*\.mediapipe-world") as info:
            read_csv(tmp_path, spec_for, mediapipe21, landmark_rows(world))
        assert info.value.field == "x"
        return
    path = tmp_path / "clip.mediapipe.json"
    points = np.concatenate([world, np.zeros(world.shape[:2] + (1,))], axis=-1)
    path.write_text(json.dumps({"frames": [{"frame": t, "landmarks": frame.tolist()}
                                           for t, frame in enumerate(points)]}))
    with pytest.raises(InputError, match="world landmarks") as info:
        mediapipe.read(path, spec_for(tmp_path, image=IMAGE), mediapipe21)
    assert info.value.field == "landmarks"


def test_a_hand_that_passes_the_image_corner_is_read(tmp_path, spec_for, mediapipe21):
    xy = world_like(mediapipe21) + np.linspace(0.0, 0.3, 6)[:, None, None]
    obs = read_csv(tmp_path, spec_for, mediapipe21, landmark_rows(xy))
    assert obs.n_rows == 6 * 21
    np.testing.assert_allclose(obs.uv[:21], xy[0] * [640, 480], atol=1e-3)


def test_landmarks_are_read_into_a_skeleton_with_more_joints(tmp_path, spec_for):
    dhg22 = load_skeleton("dhg22")
    path = tmp_path / "clip.mediapipe.csv"
    path.write_text(long_csv(hands=(0,)))
    obs = mediapipe_csv.read(path, spec_for(tmp_path, image=IMAGE, skeleton="dhg22"), dhg22)
    assert obs.n_frames == 2 and obs.n_rows == 42
    assert obs.joint.max() == dhg22.index("little_tip") == 21
