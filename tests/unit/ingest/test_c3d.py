import c3d
import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import c3d as c3d_reader
from handdb.ingest.registry import match_format
from handdb.markers.tables import dense_markers
from tests.unit.ingest.test_markers_csv import SKELETON, marker_spec, marker_track


def test_c3d_round_trip_converts_units(tmp_path):
    markers = marker_track(n_frames=6, seed=2)
    path = tmp_path / "m01.c3d"
    c3d_reader.write(path, markers, SKELETON, units="mm")
    read = dense_markers(c3d_reader.read(path, marker_spec(units="cm"), SKELETON))
    np.testing.assert_array_equal(np.isnan(read), np.isnan(markers))
    np.testing.assert_allclose(read * 10.0, markers, rtol=1e-6, atol=1e-4)
    assert match_format(path)[0].name == "c3d"


def save_counted_points(writer, path, n_points, n_frames):
    """Save ``writer`` at ``path`` with ``n_frames`` frames of points at 0, 1, 2, ... (x y z)."""
    frames = np.zeros((n_frames, n_points, 5), dtype=np.float32)
    frames[..., :3] = np.arange(n_points * 3).reshape(n_points, 3)
    writer.add_frames([(frame, np.zeros((0, 0), dtype=np.float32)) for frame in frames])
    with pytest.warns(UserWarning), path.open("wb") as handle:
        writer.write(handle)
    return path


def write_labelled(path, labels, n_frames=3, units="mm"):
    writer = c3d.Writer(point_rate=120.0, point_units=units)
    writer.set_point_labels(labels)
    return save_counted_points(writer, path, len(labels), n_frames)


@pytest.mark.parametrize("joint_map", [{"RWRA": "wrist", "STERNUM": None},
                                       {"RWRA": "wrist", "*": None}])
def test_labels_are_mapped_by_the_joint_map_and_extras_ignored_by_name(tmp_path, joint_map):
    path = write_labelled(tmp_path / "m01.c3d", ["RWRA", "index_tip", "STERNUM"])
    markers = dense_markers(c3d_reader.read(path, marker_spec(joint_map=joint_map), SKELETON))
    np.testing.assert_allclose(markers[:, SKELETON.index("wrist")], [[0, 1, 2]] * 3)
    np.testing.assert_allclose(markers[:, SKELETON.index("index_tip")], [[3, 4, 5]] * 3)
    assert np.isnan(markers[:, SKELETON.index("thumb_tip")]).all()


def test_an_unmapped_label_is_refused_as_in_every_format(tmp_path):
    path = write_labelled(tmp_path / "m01.c3d", ["RWRA", "index_tip", "STERNUM"])
    with pytest.raises(InputError, match="unknown joint 'STERNUM'.*null") as caught:
        c3d_reader.read(path, marker_spec(joint_map={"RWRA": "wrist"}), SKELETON)
    assert (caught.value.field, caught.value.line) == ("POINT:LABELS", None)


def test_c3d_whose_every_label_is_ignored_is_refused(tmp_path):
    path = write_labelled(tmp_path / "m01.c3d", ["A", "B"])
    with pytest.raises(InputError, match="none of its names") as caught:
        c3d_reader.read(path, marker_spec(joint_map={"*": None}), SKELETON)
    assert caught.value.field == "POINT:LABELS"


@pytest.mark.parametrize(("labels", "example"), [
    (["RHand:RWRA", "RHand:index_tip", "RHand:Thumb_Tip"],
     '"joint_map": {"RHand:index_tip": "index_tip", "RHand:Thumb_Tip": "thumb_tip", ...}'),
    (["A", "B"], '"joint_map": {"A": "wrist", ...}'),
])
def test_labels_of_another_convention_are_refused_with_a_joint_map_to_write(tmp_path, labels,
                                                                            example):
    path = write_labelled(tmp_path / "m01.c3d", labels)
    with pytest.raises(InputError) as caught:
        c3d_reader.read(path, marker_spec(joint_map={"*": None}), SKELETON)
    assert caught.value.reason.endswith(f"sidecar's joint_map, e.g. {example}")


def test_two_labels_for_one_joint_are_refused(tmp_path):
    path = write_labelled(tmp_path / "m01.c3d", ["wrist", "WRIST2"])
    with pytest.raises(InputError, match="'wrist' and 'WRIST2' both map to joint 'wrist'"):
        c3d_reader.read(path, marker_spec(joint_map={"WRIST2": "wrist"}), SKELETON)


def test_unknown_units_are_refused(tmp_path):
    path = write_labelled(tmp_path / "m01.c3d", ["wrist"], units="ft")
    with pytest.raises(InputError, match="units") as caught:
        c3d_reader.read(path, marker_spec(), SKELETON)
    assert caught.value.field == "POINT:UNITS"


def test_a_file_that_is_not_c3d_is_refused(tmp_path):
    path = tmp_path / "m01.c3d"
    path.write_bytes(b"frame,joint,x,y,z\n" * 40)
    with pytest.raises(InputError, match="C3D"):
        c3d_reader.read(path, marker_spec(), SKELETON)


#: The ROTATION group ezc3d and Vicon Nexus write beside the points: one orientation per
#: segment and frame, stored from block ``DATA_START`` on, at ``RATE`` (``RATIO`` per frame).
ROTATION_SEGMENTS = ("RHND", "RFRA", "RHUM")


def write_with_rotations(path, labels, n_frames=4):
    """A C3D file of points with a ROTATION group, as the c3d package's Writer lays it out."""
    writer = c3d.Writer(point_rate=120.0, point_units="mm")
    writer.set_point_labels(labels)
    group = writer.add_group(5, "ROTATION", "segment orientations")
    group.add("USED", "segments", 2, "<H", len(ROTATION_SEGMENTS))
    group.add_str("LABELS", "segment names",
                  "".join(name.ljust(4) for name in ROTATION_SEGMENTS), 4,
                  len(ROTATION_SEGMENTS))
    group.add("DATA_START", "first block of the rotations", 2, "<H", 40)
    group.add("RATE", "rotations per second", 4, "<f", 120.0)
    group.add("RATIO", "rotations per point frame", 2, "<H", 1)
    return save_counted_points(writer, path, len(labels), n_frames)


def test_rotations_beside_the_points_are_ignored(tmp_path):
    path = write_with_rotations(tmp_path / "m01.c3d", ["RWRA", "STERNUM"])
    with path.open("rb") as handle, pytest.warns(UserWarning):
        assert c3d.Reader(handle).get("ROTATION:USED").int16_value == 3, "the group is there"
    read = c3d_reader.read(path, marker_spec(joint_map={"RWRA": "wrist", "*": None}),
                           SKELETON)
    markers = dense_markers(read)
    assert markers.shape == (4, SKELETON.n_joints, 3)
    np.testing.assert_array_equal(markers[:, 0], np.tile([0.0, 1.0, 2.0], (4, 1)))
    assert np.isnan(markers[:, 1:]).all()


def test_rotations_without_points_are_refused_saying_so(tmp_path):
    path = write_with_rotations(tmp_path / "m01.c3d", ["RWRA"])
    data = bytearray(path.read_bytes())
    # POINT:USED and the header's point count set to 0: the file holds rotations only. A
    # group's record is led by its name's length and its negated id, a parameter's by the
    # name's length and the group's id, then the name, a 2-byte offset, type and rank.
    (point,) = [gid for gid in range(1, 128) if bytes([5, 256 - gid]) + b"POINT" in data]
    at = data.index(bytes([4, point]) + b"USED") + 2 + 4 + 2 + 1 + 1
    data[at:at + 2] = data[2:4] = b"\x00\x00"
    path.write_bytes(bytes(data))
    with pytest.raises(InputError) as info:
        c3d_reader.read(path, marker_spec(), SKELETON)
    assert info.value.field == "POINT:USED"
    assert "holds no 3D points (it has 3 rotations (segment orientations" in info.value.reason
    assert "export the markers to C3D" in info.value.reason


def test_gaps_written_as_the_origin_without_a_residual_are_missing(tmp_path):
    writer = c3d.Writer(point_rate=120.0, point_units="mm")
    writer.set_point_labels(["wrist", "index_tip"])
    frames = np.zeros((4, 2, 5), dtype=np.float32)
    frames[..., :3] = [[10.0, 20.0, 30.0], [40.0, 50.0, 60.0]]
    frames[1, 1, :3] = 0.0                   # a gap as an exporter without residuals writes it
    frames[2, 0, :3] = [0.0, 0.0, 5.0]       # a point on an axis is a point
    writer.add_frames([(frame, np.zeros((0, 0), dtype=np.float32)) for frame in frames])
    path = tmp_path / "m01.c3d"
    with pytest.warns(UserWarning), path.open("wb") as handle:
        writer.write(handle)
    markers = dense_markers(c3d_reader.read(path, marker_spec(fps=120.0), SKELETON))
    tip, wrist = SKELETON.index("index_tip"), SKELETON.index("wrist")
    assert np.isnan(markers[1, tip]).all()
    np.testing.assert_allclose(markers[[0, 2, 3], tip], [[40.0, 50.0, 60.0]] * 3)
    np.testing.assert_allclose(markers[2, wrist], [0.0, 0.0, 5.0])
