"""C3D export read back with the c3d package and with handdb's own C3D reader."""

import warnings

import c3d
import numpy as np

from handdb.export.c3d import export_clip_c3d
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import c3d as c3d_format
from handdb.markers.tables import dense_markers
from tests.support.axes import y_up
from tests.support.motions import make_hinge_motion
from tests.unit.ingest.test_markers_csv import marker_spec

#: float32 coordinates of a hand (under 1 m from the origin) in mm: 2**-24 * 1000 * 2.
FLOAT32_MM = 1.2e-4


def read_with_c3d_package(path):
    with path.open("rb") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        reader = c3d.Reader(handle)
        labels = [label.strip() for label in reader.point_labels]
        frames = np.stack([points for _, points, _ in reader.read_frames()])
        return {"labels": labels, "rate": reader.point_rate,
                "units": reader.get("POINT:UNITS").string_value.strip(),
                "xyz": np.where(frames[..., 3:4] < 0, np.nan, frames[..., :3])}


def test_real_capture_round_trips_through_both_readers(tmp_path, dhg_mm):
    skeleton = load_skeleton("dhg22")
    path = export_clip_c3d(tmp_path / "dhg.c3d", skeleton=skeleton, xyz=dhg_mm, fps=30.0,
                           units="mm")
    read = read_with_c3d_package(path)
    assert read["labels"] == list(skeleton.joints)
    assert (read["rate"], read["units"]) == (30.0, "mm")
    np.testing.assert_allclose(read["xyz"], y_up(dhg_mm), rtol=0, atol=FLOAT32_MM)

    spec = marker_spec(clip_id="dhg", skeleton="dhg22", fps=30.0)
    own = dense_markers(c3d_format.read(path, spec, skeleton))
    np.testing.assert_allclose(own, y_up(dhg_mm), rtol=0, atol=FLOAT32_MM)


def test_missing_joints_are_missing_points(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=10, seed=5)
    xyz = motion.xyz.copy()
    xyz[2] = np.nan
    xyz[4:6, motion.skeleton.index("thumb_tip")] = np.nan
    path = export_clip_c3d(tmp_path / "gappy.c3d", skeleton=motion.skeleton, xyz=xyz, fps=60.0,
                           units="mm")
    read = read_with_c3d_package(path)
    np.testing.assert_array_equal(np.isnan(read["xyz"]), np.isnan(xyz))
    own = dense_markers(c3d_format.read(path, marker_spec(fps=60.0), motion.skeleton))
    np.testing.assert_array_equal(np.isnan(own), np.isnan(xyz))
    np.testing.assert_allclose(own, y_up(xyz), rtol=0, atol=FLOAT32_MM)
