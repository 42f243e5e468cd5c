import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import maya


@pytest.fixture
def thesis_points(thesis21):
    """A small Maya-like motion, ``(T, 21, 3)`` camera frame."""
    rng = np.random.default_rng(3)
    base = rng.normal(0.0, 3.0, (1, thesis21.n_joints, 3))
    drift = np.linspace(0.0, 0.5, 6)[:, None, None] * rng.normal(size=(1, thesis21.n_joints, 3))
    return base + drift


def test_round_trip_gives_track_and_truth(tmp_path, spec_for, thesis21, thesis_points):
    path = tmp_path / "clip.maya.txt"
    maya.write(path, thesis_points, thesis21)
    spec = spec_for(tmp_path, skeleton="thesis21", units="cm")
    obs = maya.read(path, spec, thesis21)
    truth = maya.read_truth(path, spec, thesis21)
    assert obs.n_rows == truth.n_rows == thesis_points.shape[0] * 21
    np.testing.assert_array_equal(truth.xyz, thesis_points[truth.frame, truth.joint])
    np.testing.assert_array_equal(obs.uv, thesis_points[obs.frame, obs.joint, :2])
    assert np.isnan(obs.confidence).all()
    first = path.read_text().splitlines()[0].split()
    assert first[:2] == ["j20", "0"], "written point by point, frames in order, as the plug-in"


def test_maya_axes_become_the_camera_frame(tmp_path, spec_for, thesis21):
    path = tmp_path / "clip.maya.txt"
    path.write_text("j0 0 -4.5 -0.25 3.0\n\t j3   0\t1 2 -1.5  \r\n\nj0 1 -4.4 -0.3 2.9\n")
    spec = spec_for(tmp_path, skeleton="thesis21", units="cm")
    obs = maya.read(path, spec, thesis21)
    truth = maya.read_truth(path, spec, thesis21)
    assert obs.joint.tolist() == [thesis21.ids.index(0), thesis21.ids.index(3),
                                  thesis21.ids.index(0)]
    assert obs.frame.tolist() == [0, 0, 1]
    assert obs.line.tolist() == [1, 2, 4]
    np.testing.assert_array_equal(obs.uv, [[-4.5, 0.25], [1, -2], [-4.4, 0.3]])
    np.testing.assert_array_equal(truth.xyz[:, 2], [-3.0, 1.5, -2.9])


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    ("j0 0 1 2 3\nj1 0 1 2\n", 2, None, "has 4 fields, expected 5.*truncated"),
    ("j0 0 1 2 3\nj21 0 1 2 3\n", 2, "joint", "'j21' is not a feature point"),
    ("x0 0 1 2 3\n", 1, "joint", "'x0' is not a feature point"),
    ("j0 0 1 two 3\n", 1, "y", "'two' is not a number"),
    ("j0 0 1 2 inf\n", 1, "z", "not a finite number"),
    ("j0 -1 1 2 3\n", 1, "frame", "negative"),
    ("j0 0 1 2 3\nj1 0 1 2 3\nj0 0 1 2 3\n", 3, "frame", "given twice"),
])
def test_bad_lines(tmp_path, spec_for, thesis21, text, line, field, message):
    path = tmp_path / "clip.maya.txt"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        maya.read(path, spec_for(tmp_path, skeleton="thesis21"), thesis21)
    assert (info.value.file, info.value.line, info.value.field) == (str(path), line, field)


def test_the_sidecar_must_name_thesis21(tmp_path, spec_for, mediapipe21):
    path = tmp_path / "clip.maya.txt"
    path.write_text("j0 0 1 2 3\n")
    with pytest.raises(InputError, match="set the sidecar's skeleton") as info:
        maya.read(path, spec_for(tmp_path), mediapipe21)
    assert info.value.file == str(tmp_path / "clip.clip.json")
    assert info.value.field == "skeleton"
