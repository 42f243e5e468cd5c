"""One joint_map rule for every format: null ignores a name, "*": null every unmapped name,
unknown names and keys no file names are refused, two names for one joint are refused."""

import json

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import discover, load_clip, openpose
from handdb.ingest.sidecar import parse_sidecar

CSV = "frame,joint,u,v\n0,Wrist,1,2\n0,Elbow,3,4\n0,index_tip,5,6\n1,Wrist,1,2\n"
DLC = ("scorer,s,s,s,s,s,s\nbodyparts,Wrist,Wrist,Elbow,Elbow,index_tip,index_tip\n"
       "coords,x,y,x,y,x,y\n0,1,2,3,4,5,6\n1,1,2,,,5,6\n")
MARKERS = "frame,joint,x,y,z\n0,Wrist,1,2,3\n0,Elbow,3,4,5\n0,index_tip,5,6,7\n"
FILES = {"tracks.csv": CSV, "dlc.csv": DLC, "markers.csv": MARKERS, "truth.csv": MARKERS}


def inbox_with(tmp_path, write_sidecar, suffix, joint_map, text=None):
    write_sidecar(tmp_path, "c1", joint_map=joint_map)
    if suffix == "truth.csv":
        (tmp_path / "c1.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")
    (tmp_path / f"c1.{suffix}").write_text(text if text is not None else FILES[suffix])
    return discover(tmp_path).clips[0]


@pytest.mark.parametrize("suffix", ["tracks.csv", "dlc.csv", "markers.csv", "truth.csv"])
@pytest.mark.parametrize("ignore", [{"Elbow": None}, {"*": None}])
def test_null_and_star_ignore_names_in_every_format(tmp_path, write_sidecar, suffix, ignore):
    clip = load_clip(inbox_with(tmp_path, write_sidecar, suffix, {"Wrist": "wrist"} | ignore))
    data = {"tracks.csv": clip.uv, "dlc.csv": clip.uv, "markers.csv": clip.markers,
            "truth.csv": clip.truth}[suffix]
    seen = np.isfinite(data).all(axis=-1)
    assert [clip.skeleton.joints[j] for j in np.flatnonzero(seen.any(axis=0))] == [
        "wrist", "index_tip"]


@pytest.mark.parametrize(("suffix", "line", "field"), [
    ("tracks.csv", 3, "joint"), ("dlc.csv", 2, "bodyparts"), ("markers.csv", 3, "joint"),
    ("truth.csv", 3, "joint")])
def test_an_unmapped_name_is_refused_in_every_format(tmp_path, write_sidecar, suffix, line,
                                                     field):
    entry = inbox_with(tmp_path, write_sidecar, suffix, {"Wrist": "wrist", "Knee": None})
    with pytest.raises(InputError, match="unknown joint 'Elbow'") as info:
        load_clip(entry)
    error = info.value
    assert (error.file, error.line, error.field) == (str(tmp_path / f"c1.{suffix}"), line,
                                                     field)
    assert "Knee to null" in error.reason and "None" not in error.reason
    assert '"*": null' in error.reason


@pytest.mark.parametrize("suffix", ["tracks.csv", "dlc.csv", "markers.csv"])
def test_a_key_no_file_names_is_refused(tmp_path, write_sidecar, suffix):
    entry = inbox_with(tmp_path, write_sidecar, suffix,
                       {"Wrist": "wrist", "Elbow": None, "Wirst": "thumb_tip"})
    with pytest.raises(InputError, match=f"maps 'Wirst', which c1.{suffix} does not name"
                       ) as info:
        load_clip(entry)
    assert (info.value.file, info.value.field) == (str(tmp_path / "c1.clip.json"), "joint_map")


def test_a_key_named_by_the_truth_file_only_is_fine(tmp_path, write_sidecar):
    write_sidecar(tmp_path, "c1", joint_map={"Elbow": None})
    (tmp_path / "c1.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")
    (tmp_path / "c1.truth.csv").write_text(MARKERS.replace("Wrist", "wrist"))
    clip = load_clip(discover(tmp_path).clips[0])
    assert np.isfinite(clip.truth).all(axis=-1).sum() == 2


@pytest.mark.parametrize(("suffix", "text", "line", "field"), [
    ("tracks.csv", "frame,joint,u,v\n0,wrist,1,2\n1,Wrist,1,2\n", 3, "joint"),
    ("dlc.csv", "scorer,s,s,s,s\nbodyparts,wrist,wrist,Wrist,Wrist\ncoords,x,y,x,y\n0,1,2,3,4\n",
     2, "bodyparts"),
])
def test_two_names_for_one_joint_are_refused(tmp_path, write_sidecar, suffix, text, line,
                                             field):
    entry = inbox_with(tmp_path, write_sidecar, suffix, {"Wrist": "wrist"}, text)
    with pytest.raises(InputError, match="'wrist' and 'Wrist' both map to joint 'wrist'") as e:
        load_clip(entry)
    assert (e.value.line, e.value.field) == (line, field)


def test_fixed_order_formats_drop_a_joint_mapped_to_null(tmp_path, write_sidecar, mediapipe21,
                                                         noisy_track):
    uv, confidence = noisy_track
    openpose.write(tmp_path / "c1.openpose", uv, confidence, mediapipe21, hand="right")
    write_sidecar(tmp_path, "c1", joint_map={"thumb_cmc": None})
    clip = load_clip(discover(tmp_path).clips[0])
    assert np.isnan(clip.uv[:, mediapipe21.index("thumb_cmc")]).all()
    assert np.isfinite(clip.uv[:, mediapipe21.index("thumb_mcp")]).any()


@pytest.mark.parametrize(("joint_map", "message"), [
    ({"Wrist": "wristt"}, 'maps \'Wrist\' to "wristt", which is not a joint'),
    ({"Wrist": 5}, "maps 'Wrist' to 5"),
    ({"*": "wrist"}, "'\\*' can only be null"),
])
def test_sidecar_refuses_bad_joint_map_values(tmp_path, write_sidecar, joint_map, message):
    path = write_sidecar(tmp_path, "c1", joint_map=joint_map)
    with pytest.raises(InputError, match=message) as info:
        parse_sidecar(path)
    assert info.value.field == "joint_map" and "None" not in info.value.reason
    assert json.loads(path.read_text())["joint_map"] == joint_map, "the file is left as is"
