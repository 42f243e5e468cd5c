"""TRC export read back with an independent parser (pandas), on real and synthetic clips."""

import numpy as np
import pandas as pd
import pytest

from handdb.errors import ParameterError
from handdb.export.trc import export_clip_trc
from handdb.hand.skeletons import load_skeleton
from tests.support.axes import y_up
from tests.support.motions import make_hinge_motion


def read_trc(path):
    """Header fields, marker names and ``(T, M, 3)`` positions of a TRC file, by pandas."""
    lines = path.read_text().split("\n")
    fields = dict(zip(lines[1].split("\t"), lines[2].split("\t"), strict=True))
    names = [name for name in lines[3].split("\t")[2:] if name]
    axes = lines[4].split("\t")[2:]
    data = pd.read_csv(path, sep="\t", skiprows=5, header=None)
    values = data.iloc[:, 2:].to_numpy(dtype=float).reshape(len(data), len(names), 3)
    return {"file_type": lines[0].split("\t"), "fields": fields, "names": names, "axes": axes,
            "frame": data[0].to_numpy(), "time": data[1].to_numpy(), "xyz": values}


def test_real_capture_reads_back_in_mm(tmp_path, dhg_mm):
    skeleton = load_skeleton("dhg22")
    path = export_clip_trc(tmp_path / "dhg.trc", skeleton=skeleton, xyz=dhg_mm, fps=30.0,
                           units="mm")
    trc = read_trc(path)
    assert trc["file_type"] == ["PathFileType", "4", "(X/Y/Z)", "dhg.trc"]
    assert trc["fields"] == {"DataRate": "30", "CameraRate": "30", "NumFrames": "95",
                             "NumMarkers": "22", "Units": "mm", "OrigDataRate": "30",
                             "OrigDataStartFrame": "1", "OrigNumFrames": "95"}
    assert trc["names"] == list(skeleton.joints)
    assert trc["axes"][:4] == ["X1", "Y1", "Z1", "X2"] and len(trc["axes"]) == 66
    np.testing.assert_array_equal(trc["frame"], np.arange(1, 96))
    np.testing.assert_allclose(trc["time"], np.arange(95) / 30.0, atol=1e-6)
    np.testing.assert_allclose(trc["xyz"], y_up(dhg_mm), atol=1e-6)
    # Y up: the real hand's wrist is below its fingertips in the image (camera y down).
    assert np.isclose(trc["xyz"][:, 0, 1], -dhg_mm[:, 0, 1]).all()


def test_missing_joints_are_empty_cells(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=12, seed=4)
    xyz = motion.xyz.copy()
    xyz[3] = np.nan
    xyz[5:8, motion.skeleton.index("index_tip")] = np.nan
    path = export_clip_trc(tmp_path / "gappy.trc", skeleton=motion.skeleton, xyz=xyz, fps=25.0,
                           units="cm")
    trc = read_trc(path)
    assert trc["fields"]["Units"] == "cm"
    np.testing.assert_array_equal(np.isnan(trc["xyz"]), np.isnan(xyz))
    np.testing.assert_allclose(trc["xyz"], y_up(xyz), atol=1e-6)
    row_4 = path.read_text().split("\n")[5 + 3].split("\t")
    assert row_4[:2] == ["4", "0.120000"] and row_4[2:] == [""] * 63


def test_bad_parameters_are_refused(tmp_path):
    skeleton = load_skeleton("mediapipe21")
    with pytest.raises(ParameterError, match="fps must be positive"):
        export_clip_trc(tmp_path / "x.trc", skeleton=skeleton, xyz=np.zeros((2, 21, 3)),
                        fps=0.0, units="mm")
    with pytest.raises(ParameterError, match=r"xyz must be \(T, 21, 3\)"):
        export_clip_trc(tmp_path / "x.trc", skeleton=skeleton, xyz=np.zeros((2, 20, 3)),
                        fps=30.0, units="mm")
    with pytest.raises(ParameterError, match="units must be one of"):
        export_clip_trc(tmp_path / "x.trc", skeleton=skeleton, xyz=np.zeros((2, 21, 3)),
                        fps=30.0, units="furlong")
    assert not (tmp_path / "x.trc").exists()
