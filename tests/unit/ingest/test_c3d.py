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


def write_labelled(path, labels, n_frames=3, units="mm"):
    writer = c3d.Writer(point_rate=120.0, point_units=units)
    writer.set_point_labels(labels)
    frames = np.zeros((n_frames, len(labels), 5), dtype=np.float32)
    frames[..., :3] = np.arange(len(labels) * 3).reshape(len(labels), 3)
    writer.add_frames([(frame, np.zeros((0, 0), dtype=np.float32)) for frame in frames])
    with pytest.warns(UserWarning), path.open("wb") as handle:
        writer.write(handle)
    return path


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
