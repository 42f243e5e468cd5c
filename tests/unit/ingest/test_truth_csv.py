import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import truth_csv


def test_round_trip_skips_points_without_truth(tmp_path, spec_for, mediapipe21):
    xyz = np.random.default_rng(4).normal(0.0, 50.0, (5, 21, 3))
    xyz[2, 7] = np.nan
    path = tmp_path / "clip.truth.csv"
    truth_csv.write(path, xyz, mediapipe21)
    truth = truth_csv.read(path, spec_for(tmp_path), mediapipe21)
    assert truth.n_rows == 5 * 21 - 1
    np.testing.assert_array_equal(truth.xyz, xyz[truth.frame, truth.joint])


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    ("frame,joint,x,y,z\n0,wrist,1,,3\n", 2, "y", "is empty; a value is required"),
    ("frame,joint,x,y\n0,wrist,1,2\n", 1, "z", "lacks column 'z'"),
    ("frame,joint,x,y,z\n0,wrist,1,2,NaN\n", 2, "z", "not a finite number"),
    ("frame,joint,x,y,z\n0,wrist,1,2,3\n0,wrist,1,2,3\n", 3, "frame", "given twice"),
    ("frame,joint,x,y,z\n0,elbow,1,2,3\n", 2, "joint", "unknown joint 'elbow'"),
])
def test_bad_truth_rows(tmp_path, spec_for, mediapipe21, text, line, field, message):
    path = tmp_path / "clip.truth.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        truth_csv.read(path, spec_for(tmp_path), mediapipe21)
    assert (info.value.file, info.value.line, info.value.field) == (str(path), line, field)
