import numpy as np
import pytest

from handdb.clip import Camera, ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import markers_csv
from handdb.ingest.registry import match_format
from handdb.markers.tables import dense_markers, markers_3d_table
from handdb.store.tables import schema

SKELETON = load_skeleton("mediapipe21")


def marker_spec(**overrides) -> ClipSpec:
    values = dict(clip_id="m01", path="m01.clip.json", skeleton="mediapipe21", hand="right",
                  fps=120.0, subject="s01", units="mm", camera=Camera())
    values.update(overrides)
    return ClipSpec(**values)


def marker_track(n_frames=5, seed=0):
    rng = np.random.default_rng(seed)
    markers = rng.normal(0.0, 60.0, (n_frames, SKELETON.n_joints, 3))
    markers[rng.random((n_frames, SKELETON.n_joints)) < 0.3] = np.nan
    return markers


def write_text(tmp_path, text):
    path = tmp_path / "m01.markers.csv"
    path.write_text(text)
    return path


def test_markers_round_trip_with_missing_markers(tmp_path):
    markers = marker_track()
    path = tmp_path / "m01.markers.csv"
    markers_csv.write(path, markers, SKELETON)
    read = dense_markers(markers_csv.read(path, marker_spec(), SKELETON))
    np.testing.assert_array_equal(np.isnan(read), np.isnan(markers))
    np.testing.assert_allclose(read, markers)


def test_the_inbox_knows_marker_files(tmp_path):
    fmt, clip_id = match_format(write_text(tmp_path, "frame,joint,x,y,z\n0,wrist,1,2,3\n"))
    assert (fmt.name, fmt.kind, clip_id) == ("markers_csv", "markers", "m01")


def test_joint_map_names_markers(tmp_path):
    path = write_text(tmp_path, "frame,joint,x,y,z\n0,RWRA,1,2,3\n2,index_tip,4,5,6\n")
    spec = marker_spec(joint_map={"RWRA": "wrist"})
    markers = dense_markers(markers_csv.read(path, spec, SKELETON))
    assert markers.shape == (3, 21, 3)
    np.testing.assert_array_equal(markers[0, 0], [1, 2, 3])
    assert np.isnan(markers[1]).all()


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    ("frame,joint,x,y\n0,wrist,1,2\n", 1, "z", "lacks column"),
    ("frame,joint,x,y,z\n0,wrist,1,2,3\n1,thumb,1,2,3\n", 3, "joint", "unknown joint"),
    ("frame,joint,x,y,z\n0,wrist,1,2,3\n0.5,wrist,1,2,3\n", 3, "frame", "whole frame"),
    ("frame,joint,x,y,z\n-1,wrist,1,2,3\n", 2, "frame", "negative"),
    ("frame,joint,x,y,z\n0,wrist,1,,3\n", 2, "y", "empty"),
    ("frame,joint,x,y,z\n0,wrist,1,2,abc\n", 2, "z", "not a number"),
    ("frame,joint,x,y,z\n0,wrist,1,2,3\n0,wrist,4,5,6\n", 3, "frame", "twice"),
])
def test_bad_marker_files_name_line_and_field(tmp_path, text, line, field, message):
    with pytest.raises(InputError, match=message) as caught:
        markers_csv.read(write_text(tmp_path, text), marker_spec(), SKELETON)
    assert (caught.value.line, caught.value.field) == (line, field)
    assert caught.value.file.endswith("m01.markers.csv")


def test_empty_marker_file_is_refused(tmp_path):
    with pytest.raises(InputError, match="empty"):
        markers_csv.read(write_text(tmp_path, ""), marker_spec(), SKELETON)


def test_markers_3d_rows_are_the_markers_seen():
    markers = marker_track(n_frames=4, seed=1)
    table = markers_3d_table("m01", markers, SKELETON)
    assert table.schema.equals(schema("markers_3d"))
    seen = np.isfinite(markers).all(axis=-1)
    assert table.num_rows == seen.sum()
    frame = np.array(table.column("frame"))
    joint = np.array(table.column("joint_index"))
    np.testing.assert_array_equal(np.array(table.column("x")), markers[frame, joint, 0])
