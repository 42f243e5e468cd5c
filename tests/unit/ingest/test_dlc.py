import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import dlc

HEADER = ("scorer,DLC_resnet50,DLC_resnet50,DLC_resnet50,DLC_resnet50,DLC_resnet50,DLC_resnet50\n"
          "bodyparts,Wrist,Wrist,Wrist,IndexTip,IndexTip,IndexTip\n"
          "coords,x,y,likelihood,x,y,likelihood\n")
JOINT_MAP = {"Wrist": "wrist", "IndexTip": "index_tip"}


def read_text(tmp_path, spec_for, skeleton, text, **sidecar):
    path = tmp_path / "clip.dlc.csv"
    path.write_text(text)
    spec = spec_for(tmp_path, **({"joint_map": JOINT_MAP} | sidecar))
    return dlc.read(path, spec, skeleton)


def test_round_trip_with_tool_names_and_individuals(tmp_path, spec_for, mediapipe21,
                                                    noisy_track):
    uv, confidence = noisy_track
    tool_names = {joint: f"bp_{k}" for k, joint in enumerate(mediapipe21.joints)}
    path = tmp_path / "clip.dlc.csv"
    dlc.write(path, uv, confidence, mediapipe21, bodyparts=tool_names, individual="hand1")
    spec = spec_for(tmp_path, joint_map={v: k for k, v in tool_names.items()})
    obs = dlc.read(path, spec, mediapipe21)
    assert obs.n_rows == uv.shape[0] * 21
    np.testing.assert_array_equal(obs.uv, uv[obs.frame, obs.joint])
    np.testing.assert_array_equal(obs.confidence, confidence[obs.frame, obs.joint])
    np.testing.assert_array_equal(obs.line, np.repeat(np.arange(5, 5 + uv.shape[0]), 21))


def test_empty_cells_are_missing_and_likelihood_is_optional(tmp_path, spec_for, mediapipe21):
    text = "scorer,s,s\nbodyparts,wrist,wrist\ncoords,x,y\n0,1.5,2.5\n1,,\n"
    obs = read_text(tmp_path, spec_for, mediapipe21, text)
    assert obs.uv[0].tolist() == [1.5, 2.5]
    assert np.isnan(obs.uv[1]).all() and np.isnan(obs.confidence).all()


@pytest.mark.parametrize(("rows", "line", "field", "message"), [
    ("0,1,2,0.9,3,4,0.8\n1,1,2,0.9,3,4\n", 5, None, "has 6 fields, expected 7.*truncated"),
    ("0,1,2,0.9,3,four,0.8\n", 4, "IndexTip.y", "'four' is not a number"),
    ("0,1,2,0.9,3,nan,0.8\n", 4, "IndexTip.y", "not a finite number; leave the cell empty"),
    ("0,1,2,1.2,3,4,0.8\n", 4, "Wrist.likelihood", "confidence 1.2 lies outside"),
    ("0,1,,0.9,3,4,0.8\n", 4, "Wrist.y", "is empty but its partner"),
    ("0,1,2,0.9,3,4,0.8\n-2,1,2,0.9,3,4,0.8\n", 5, "frame", "frame -2 is negative"),
    ("0,1,2,0.9,3,4,0.8\n0,1,2,0.9,3,4,0.8\n", 5, "frame", "given twice"),
    ("", 3, None, "has header rows but no data rows"),
])
def test_bad_data_rows(tmp_path, spec_for, mediapipe21, rows, line, field, message):
    with pytest.raises(InputError, match=message) as info:
        read_text(tmp_path, spec_for, mediapipe21, HEADER + rows)
    assert info.value.file == str(tmp_path / "clip.dlc.csv")
    assert (info.value.line, info.value.field) == (line, field)


def test_bodyparts_that_do_not_map_are_refused(tmp_path, spec_for, mediapipe21):
    with pytest.raises(InputError, match="unknown joint 'IndexTip'") as info:
        read_text(tmp_path, spec_for, mediapipe21, HEADER + "0,1,2,0.9,3,4,0.8\n",
                  joint_map={"Wrist": "wrist"})
    assert (info.value.line, info.value.field) == (2, "bodyparts")
    assert "joint_map" in info.value.reason and "index_tip" in info.value.reason


@pytest.mark.parametrize(("header", "line", "field", "message"), [
    ("frame,u,v\n0,1,2\n", 1, "scorer", "not a DeepLabCut CSV"),
    ("scorer,s,s\ncoords,x,y\n0,1,2\n", 2, "bodyparts", "expected 'bodyparts'"),
    ("scorer,s,s\nbodyparts,wrist,wrist\ncoords,x,z\n0,1,2\n", 3, "coords", "'z' of body part"),
    ("scorer,s,s\nbodyparts,wrist,wrist\ncoords,x,x\n0,1,2\n", 3, "wrist", "two 'x' columns"),
    ("scorer,s,s,s\nbodyparts,wrist,wrist,wrist\ncoords,x,likelihood,likelihood\n", 3, "wrist",
     "two 'likelihood'"),
    ("scorer,s\nbodyparts,wrist\ncoords,x\n0,1\n", 3, "wrist", "has no 'y' column"),
    ("scorer,s,s,s\nbodyparts,wrist,wrist\ncoords,x,y\n", 2, None, "different numbers of cells"),
    ("scorer,s,s,s,s\nindividuals,a,a,b,b\nbodyparts,wrist,wrist,wrist,wrist\n"
     "coords,x,y,x,y\n0,1,2,3,4\n", 2, "individuals", "holds 2 individuals"),
    ("scorer,s,s,s,s\nbodyparts,wrist,wrist,WRIST,WRIST\ncoords,x,y,x,y\n0,1,2,3,4\n", 2,
     "bodyparts", "'wrist' and 'WRIST' both map to joint 'wrist'"),
])
def test_bad_headers(tmp_path, spec_for, mediapipe21, header, line, field, message):
    with pytest.raises(InputError, match=message) as info:
        read_text(tmp_path, spec_for, mediapipe21, header, joint_map={"WRIST": "wrist"})
    assert (info.value.line, info.value.field) == (line, field)


def test_empty_columns_after_the_last_body_part_are_ignored(tmp_path, spec_for, mediapipe21):
    rows = [line + ",," for line in (HEADER + "0,1,2,0.9,3,4,0.8\n").splitlines()]
    obs = read_text(tmp_path, spec_for, mediapipe21, "\n".join(rows) + "\n")
    assert obs.uv.tolist() == [[1.0, 2.0], [3.0, 4.0]]


def test_a_semicolon_separated_file_is_refused_with_what_to_save(tmp_path, spec_for,
                                                                  mediapipe21):
    text = (HEADER + "0,1.5,2,0.9,3,4,0.8\n").replace(",", ";").replace("1.5", "1,5")
    with pytest.raises(InputError, match="separates its fields with semicolons") as info:
        read_text(tmp_path, spec_for, mediapipe21, text)
    assert (info.value.line, info.value.field) == (1, "scorer")
