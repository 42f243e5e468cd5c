import json

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import openpose


def keypoint_file(folder, frame, people, name="clip"):
    folder.mkdir(exist_ok=True)
    path = folder / f"{name}_{frame:012d}_keypoints.json"
    path.write_text(json.dumps({"version": 1.3, "people": people}))
    return path


def hand(points, side="right"):
    return {"pose_keypoints_2d": [], f"hand_{side}_keypoints_2d": points}


def test_round_trip_marks_zero_points_missing(tmp_path, spec_for, mediapipe21, noisy_track):
    uv, confidence = noisy_track
    folder = tmp_path / "clip.openpose"
    openpose.write(folder, uv, confidence, mediapipe21, hand="right")
    obs = openpose.read(folder, spec_for(tmp_path), mediapipe21)
    present = np.isfinite(uv).all(axis=-1)
    assert obs.n_frames == uv.shape[0]
    assert 3 not in obs.frame, "a frame without points is written and read with no people"
    reported = present[obs.frame, obs.joint]
    np.testing.assert_array_equal(obs.uv[reported], uv[obs.frame, obs.joint][reported])
    assert np.isnan(obs.uv[~reported]).all()
    np.testing.assert_array_equal(obs.confidence[~reported], 0.0)
    np.testing.assert_array_equal(obs.confidence[reported],
                                  confidence[obs.frame, obs.joint][reported])


def test_frames_come_from_file_names_and_the_sidecar_picks_the_hand(tmp_path, spec_for,
                                                                    mediapipe21):
    folder = tmp_path / "clip.openpose"
    right = [0.0] * 63
    left = [5.0, 6.0, 0.75] + [0.0] * 60
    keypoint_file(folder, 10, [hand(right) | hand(left, "left")])
    keypoint_file(folder, 9, [hand(right) | hand(left, "left")])
    keypoint_file(folder, 11, [])
    keypoint_file(folder, 8, [hand([]) | hand([], "left")])
    (folder / "notes.txt").write_text("ignored")
    obs = openpose.read(folder, spec_for(tmp_path, hand="left"), mediapipe21)
    assert obs.n_frames == 12
    assert sorted(set(obs.frame.tolist())) == [9, 10]
    wrist = obs.uv[(obs.joint == 0)]
    np.testing.assert_array_equal(wrist, [[5.0, 6.0], [5.0, 6.0]])
    assert obs.files[obs.source[0]].endswith("clip_000000000009_keypoints.json")


def test_thesis_skeleton_drops_the_joint_it_lacks(tmp_path, spec_for, mediapipe21, thesis21,
                                                  noisy_track):
    uv, confidence = noisy_track
    folder = tmp_path / "clip.openpose"
    openpose.write(folder, uv, confidence, mediapipe21, hand="right")
    obs = openpose.read(folder, spec_for(tmp_path, skeleton="thesis21"), thesis21)
    assert thesis21.index("palm_fold") not in obs.joint
    assert len(set(obs.joint.tolist())) == 20


@pytest.mark.parametrize(("people", "field", "message"), [
    ([hand([1.0] * 60)], "people[0].hand_right_keypoints_2d", "has 60 numbers.*63"),
    ([hand("abc")], "people[0].hand_right_keypoints_2d", "must be a list of numbers, got str"),
    ([hand([1.0] * 62 + ["x"])], "people[0].hand_right_keypoints_2d", "list of numbers"),
    ([hand([1.0] * 63, "left")], "people[0].hand_right_keypoints_2d", "no right hand"),
    ([hand([float("nan")] + [1.0] * 62)], "people[0].hand_right_keypoints_2d", "NaN"),
])
def test_bad_keypoint_arrays_name_the_frame_file(tmp_path, spec_for, mediapipe21, people, field,
                                                  message):
    folder = tmp_path / "clip.openpose"
    keypoint_file(folder, 0, [hand([1.0, 2.0, 0.9] * 21)])
    bad = keypoint_file(folder, 1, people)
    with pytest.raises(InputError, match=message) as info:
        openpose.read(folder, spec_for(tmp_path), mediapipe21)
    assert (info.value.file, info.value.field) == (str(bad), field)


def test_confidence_outside_unit_range_names_the_keypoint(tmp_path, spec_for, mediapipe21):
    folder = tmp_path / "clip.openpose"
    bad = keypoint_file(folder, 0, [hand([1.0, 2.0, 0.9] * 20 + [1.0, 2.0, 7.0])])
    with pytest.raises(InputError, match="confidence 7.0 lies outside") as info:
        openpose.read(folder, spec_for(tmp_path), mediapipe21)
    assert info.value.file == str(bad)
    assert info.value.field == "people[0].hand_right_keypoints_2d[little_tip].c"


def test_truncated_json_names_file_and_line(tmp_path, spec_for, mediapipe21):
    folder = tmp_path / "clip.openpose"
    good = keypoint_file(folder, 0, [hand([1.0, 2.0, 0.9] * 21)])
    cut = folder / "clip_000000000001_keypoints.json"
    cut.write_text(json.dumps({"people": [hand([1.0] * 63)]}, indent=1)[:150])
    with pytest.raises(InputError, match="not valid JSON.*truncated") as info:
        openpose.read(folder, spec_for(tmp_path), mediapipe21)
    assert info.value.file == str(cut) and info.value.line > 1
    assert good.exists()


@pytest.mark.parametrize(("content", "message"), [
    ("", "is empty"),
    ("[1, 2]", "needs a 'people' list"),
])
def test_files_that_are_not_openpose_output(tmp_path, spec_for, mediapipe21, content, message):
    folder = tmp_path / "clip.openpose"
    folder.mkdir()
    (folder / "clip_000000000000_keypoints.json").write_text(content)
    with pytest.raises(InputError, match=message):
        openpose.read(folder, spec_for(tmp_path), mediapipe21)


def test_empty_folder_and_repeated_frame_numbers(tmp_path, spec_for, mediapipe21):
    folder = tmp_path / "clip.openpose"
    folder.mkdir()
    with pytest.raises(InputError, match="holds no"):
        openpose.read(folder, spec_for(tmp_path), mediapipe21)
    keypoint_file(folder, 4, [], name="a")
    keypoint_file(folder, 4, [], name="b")
    with pytest.raises(InputError, match="frame 4 is also in a_000000000004") as info:
        openpose.read(folder, spec_for(tmp_path), mediapipe21)
    assert info.value.file.endswith("b_000000000004_keypoints.json")


def two_people(folder, order_by_frame, step=2.0):
    """Two signers 300 px apart, moving ``step`` px a frame, listed in the given orders."""
    for frame, order in enumerate(order_by_frame):
        signers = []
        for x in (100.0, 400.0):
            points = np.tile([x + step * frame, 200.0, 0.9], 21)
            points[0::3] += np.arange(21)
            signers.append({"person_id": [-1], "pose_keypoints_2d": [x, 150.0, 0.8],
                            "hand_right_keypoints_2d": points.tolist()})
        keypoint_file(folder, frame, [signers[k] for k in order])


def test_people_who_trade_places_without_tracking_are_refused(tmp_path, spec_for,
                                                               mediapipe21):
    folder = tmp_path / "clip.openpose"
    two_people(folder, [(0, 1)] * 3 + [(1, 0)] * 3)
    with pytest.raises(InputError, match=r"people\[1\] here is people\[0\] of "
                       r"clip_000000000002_keypoints.json.*--tracking 1") as info:
        openpose.read(folder, spec_for(tmp_path, person=1), mediapipe21)
    assert info.value.file.endswith("clip_000000000003_keypoints.json")
    assert info.value.field == "people"


@pytest.mark.parametrize("step", [2.0, 40.0])
def test_people_who_keep_their_places_are_read_by_index(tmp_path, spec_for, mediapipe21,
                                                        step):
    folder = tmp_path / "clip.openpose"
    two_people(folder, [(0, 1)] * 6, step=step)
    obs = openpose.read(folder, spec_for(tmp_path, person=1), mediapipe21)
    wrists = obs.uv[obs.joint == 0]
    np.testing.assert_allclose(wrists[:, 0], 400.0 + step * np.arange(6))


def test_one_person_detected_twice_is_read_whichever_is_listed_first(tmp_path, spec_for,
                                                                     mediapipe21):
    """OpenPose's duplicate detections, a pixel apart and listed in either order, are one
    signer: their order is never refused as a trade of places."""
    folder = tmp_path / "clip.openpose"
    jitter = np.random.default_rng(0).normal(scale=0.5, size=(6, 2))
    for frame, order in enumerate([(0, 1), (1, 0)] * 3):
        copies = []
        for offset in (0.0, 1.0):
            points = np.tile([200.0 + offset + jitter[frame, 0], 200.0 + jitter[frame, 1],
                              0.9], 21)
            points[0::3] += np.arange(21)
            copies.append({"person_id": [-1], "hand_right_keypoints_2d": points.tolist()})
        keypoint_file(folder, frame, [copies[k] for k in order])
    obs = openpose.read(folder, spec_for(tmp_path, person=1), mediapipe21)
    assert obs.n_frames == 6
