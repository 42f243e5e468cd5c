import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import discover, load_clip, tracks_csv
from tests.unit.ingest.conftest import hand_track


def read_text(tmp_path, spec_for, skeleton, text, **sidecar):
    path = tmp_path / "clip.tracks.csv"
    path.write_text(text)
    return path, tracks_csv.read(path, spec_for(tmp_path, **sidecar), skeleton)


def test_round_trip_keeps_points_confidence_and_lines(tmp_path, spec_for, mediapipe21,
                                                      noisy_track):
    uv, confidence = noisy_track
    path = tmp_path / "clip.tracks.csv"
    tracks_csv.write(path, uv, confidence, mediapipe21)
    obs = tracks_csv.read(path, spec_for(tmp_path), mediapipe21)
    np.testing.assert_array_equal(obs.uv, uv[obs.frame, obs.joint])
    np.testing.assert_array_equal(obs.confidence, confidence[obs.frame, obs.joint])
    np.testing.assert_array_equal(obs.line, np.arange(2, obs.n_rows + 2))
    assert obs.n_frames == uv.shape[0]
    assert obs.n_rows == np.count_nonzero(np.isfinite(confidence))


def test_empty_coordinates_are_a_missing_point_and_confidence_is_optional(
        tmp_path, spec_for, mediapipe21):
    _, obs = read_text(tmp_path, spec_for, mediapipe21,
                       "frame,joint,u,v\n0,wrist,10.5,20\n0,index_tip,,\n2,wrist,11,21\n")
    assert obs.n_rows == 3 and obs.n_frames == 3
    assert np.isnan(obs.uv[1]).all()
    assert np.isnan(obs.confidence).all()
    assert obs.joint.tolist() == [0, mediapipe21.index("index_tip"), 0]


def test_spreadsheet_export_with_byte_order_mark_and_crlf(tmp_path, spec_for, mediapipe21):
    path = tmp_path / "clip.tracks.csv"
    path.write_bytes("frame,joint,u,v\r\n0,wrist,1,2\r\n".encode("utf-8-sig"))
    obs = tracks_csv.read(path, spec_for(tmp_path), mediapipe21)
    assert obs.uv.tolist() == [[1.0, 2.0]]


def test_joint_map_names_and_blank_lines_keep_line_numbers(tmp_path, spec_for, mediapipe21):
    text = "frame,joint,u,v,confidence\n\n0,WRIST,1,2,0.9\r\n\n1,tip8,3,4,1\n"
    _, obs = read_text(tmp_path, spec_for, mediapipe21, text,
                       joint_map={"WRIST": "wrist", "tip8": "index_tip"})
    assert obs.joint.tolist() == [0, mediapipe21.index("index_tip")]
    assert obs.line.tolist() == [3, 5]


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    ("frame,joint,u,v\n0,wrist,1,2\n1,wrist,1\n", 3, None, "has 3 fields, expected 4.*truncated"),
    ("frame,joint,u,v\n0,wrist,1,2,3\n1,wrist,1,2\n", 2, None, "has 5 fields"),
    ("frame,joint,u,v\n0,wrist,1,2\n1,wrist,abc,2\n", 3, "u", "'abc' is not a number"),
    ("frame,joint,u,v\n0,wrist,1,NaN\n", 2, "v", "'NaN' is not a finite number"),
    ("frame,joint,u,v\n0,wrist,-inf,2\n", 2, "u", "'-inf' is not a finite number"),
    ("frame,joint,u,v\n0,wrist,1e999,2\n", 2, "u", "'1e999' is not a finite number"),
    ("frame,joint,u,v\n0,wrist,1,2\n-1,wrist,1,2\n", 3, "frame", "frame -1 is negative"),
    ("frame,joint,u,v\n0.5,wrist,1,2\n", 2, "frame", "'0.5' is not a whole frame number"),
    ("frame,joint,u,v\n0,wrist,1,\n", 2, "v", "is empty but its partner"),
    ("frame,joint,u,v,confidence\n0,wrist,1,2,1.5\n", 2, "confidence",
     "confidence 1.5 lies outside"),
    ("frame,joint,u,v,confidence\n0,wrist,1,2,-0.1\n", 2, "confidence", "outside"),
    ("frame,joint,u\n0,wrist,1\n", 1, "v", "the header lacks column 'v'"),
    ("frame,joint,u,v,conf\n0,wrist,1,2,1\n", 1, "conf", "unknown column 'conf'"),
    ("frame,joint,u,v,u\n0,wrist,1,2,1\n", 1, "u", "column named twice"),
    ("frame,joint,u,v\n", 1, None, "has a header but no data rows"),
])
def test_bad_rows_are_refused_with_file_line_and_field(tmp_path, spec_for, mediapipe21, text,
                                                       line, field, message):
    with pytest.raises(InputError, match=message) as info:
        read_text(tmp_path, spec_for, mediapipe21, text)
    assert info.value.file == str(tmp_path / "clip.tracks.csv")
    assert (info.value.line, info.value.field) == (line, field)


def test_unknown_joint_names_the_known_joints_and_joint_map(tmp_path, spec_for, mediapipe21):
    text = "frame,joint,u,v\n0,wrist,1,2\n0,pinky_tip,3,4\n"
    with pytest.raises(InputError) as info:
        read_text(tmp_path, spec_for, mediapipe21, text, joint_map={"WRIST": "wrist"})
    error = info.value
    assert (error.line, error.field) == (3, "joint")
    assert "unknown joint 'pinky_tip'" in error.reason
    assert "little_tip" in error.reason and "joint_map maps WRIST" in error.reason


def test_duplicate_frame_joint_names_both_lines(tmp_path, spec_for, mediapipe21):
    text = "frame,joint,u,v\n0,wrist,1,2\n0,thumb_tip,1,2\n1,wrist,1,2\n0,wrist,5,6\n"
    with pytest.raises(InputError, match="frame 0 joint 'wrist' is given twice") as info:
        read_text(tmp_path, spec_for, mediapipe21, text)
    assert info.value.line == 5
    assert f"{tmp_path / 'clip.tracks.csv'}:2" in info.value.reason


@pytest.mark.parametrize("text", ["", "\n  \n"])
def test_empty_file_is_refused(tmp_path, spec_for, mediapipe21, text):
    with pytest.raises(InputError, match="is empty"):
        read_text(tmp_path, spec_for, mediapipe21, text)


def test_first_bad_row_of_a_large_file_is_located(tmp_path, spec_for, mediapipe21):
    n_frames = 20_000
    frame = np.repeat(np.arange(n_frames), 21)
    joints = np.tile(np.asarray(mediapipe21.joints), n_frames)
    rows = [f"{f},{j},1.5,2.5" for f, j in zip(frame, joints, strict=True)]
    rows[300_000] = rows[300_000].replace("1.5", "x1.5")
    with pytest.raises(InputError, match="'x1.5' is not a number") as info:
        read_text(tmp_path, spec_for, mediapipe21, "frame,joint,u,v\n" + "\n".join(rows))
    assert info.value.line == 300_002


@pytest.mark.parametrize("text", [
    ",frame,joint,u,v\n0,0,wrist,1,2\n1,1,index_tip,3,4\n",           # pandas' index column
    "frame,joint,u,v,,\n0,wrist,1,2,,\n1,index_tip,3,4,,\n",          # a spreadsheet's
])
def test_columns_without_a_name_are_ignored(tmp_path, spec_for, mediapipe21, text):
    _, obs = read_text(tmp_path, spec_for, mediapipe21, text)
    assert obs.uv.tolist() == [[1.0, 2.0], [3.0, 4.0]]
    assert obs.joint.tolist() == [0, mediapipe21.index("index_tip")]


@pytest.mark.parametrize(("text", "name"), [
    ("frame;joint;u;v\n0;wrist;1,5;2\n", "semicolons"),
    ("frame\tjoint\tu\tv\n0\twrist\t1.5\t2\n", "tabs"),
])
def test_other_separators_are_refused_with_what_to_save(tmp_path, spec_for, mediapipe21,
                                                         text, name):
    with pytest.raises(InputError, match=f"separates its fields with {name}, not ','.*'.' in "
                       "decimals") as info:
        read_text(tmp_path, spec_for, mediapipe21, text)
    assert (info.value.line, info.value.field) == (1, "frame")


@pytest.mark.parametrize(("scale", "refused"), [(1.0, True), (640.0, False)])
def test_a_track_normalised_to_the_image_is_refused_as_not_pixels(tmp_path, write_sidecar,
                                                                  mediapipe21, scale, refused):
    track = hand_track(mediapipe21, 4)
    normalised = track / track.max()                                    # within [0, 1]
    write_sidecar(tmp_path, "clip")
    tracks_csv.write(tmp_path / "clip.tracks.csv", normalised * scale, None, mediapipe21)
    (entry,) = discover(tmp_path).clips
    if not refused:
        np.testing.assert_allclose(load_clip(entry).uv, normalised * scale)
        return
    with pytest.raises(InputError, match="normalised to the image, not pixels") as info:
        load_clip(entry)
    assert info.value.field == "u" and info.value.line > 1
