"""A stored clip as an xarray dataset in movement's layout, and as a pandas frame."""

import numpy as np
import pytest

import handdb
from handdb.build import BuildOptions, build_in_process
from handdb.errors import UnknownNameError
from handdb.hand.skeletons import load_skeleton
from handdb.store.dataset import points_frame
from handdb.store.query import query


@pytest.fixture(scope="module")
def db(tmp_path_factory, write_clip):
    inbox = tmp_path_factory.mktemp("load") / "inbox"
    inbox.mkdir()
    for seed, clip_id in enumerate(["alpha", "bravo"]):
        write_clip(inbox, clip_id, seed=seed)
    db = str(inbox.parent / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == ["alpha", "bravo"]
    return db


def test_a_clip_loads_with_the_tables_values_in_movements_layout(db):
    dataset = handdb.load_clip(db, "bravo")
    [clip] = query(db, "SELECT * FROM clips WHERE clip_id = 'bravo'").to_pylist()
    joints = load_skeleton(clip["skeleton"]).joints
    assert dataset.position.dims == ("time", "keypoints", "space")
    assert dataset.sizes == {"time": clip["n_frames"], "keypoints": len(joints), "space": 3}
    assert list(dataset.keypoints.values) == list(joints)
    np.testing.assert_allclose(dataset.time.values, np.arange(clip["n_frames"]) / clip["fps"])
    rows = query(db, "SELECT frame, joint_index, x, y, z, u, confidence, observed "
                     "FROM joints_3d WHERE clip_id = 'bravo'").to_pydict()
    frame, joint = np.array(rows["frame"]), np.array(rows["joint_index"])
    for axis in "xyz":
        np.testing.assert_array_equal(dataset.position.sel(space=axis).values[frame, joint],
                                      rows[axis])
    np.testing.assert_array_equal(dataset.u.values[frame, joint], rows["u"])
    np.testing.assert_array_equal(dataset.observed.values[frame, joint], rows["observed"])
    assert dataset.attrs["units"] == clip["units"] and dataset.attrs["fps"] == clip["fps"]
    assert dataset.attrs["clip_id"] == "bravo" and dataset.attrs["source"] == "handdb"


def test_points_frame_has_one_row_per_frame_and_joint(db):
    dataset = handdb.load_clip(db, "alpha")
    frame = points_frame(dataset)
    assert len(frame) == dataset.sizes["time"] * dataset.sizes["keypoints"]
    wrist = frame[(frame.frame == 3) & (frame.keypoints == "wrist")]
    np.testing.assert_array_equal(wrist[["x", "y", "z"]].to_numpy()[0],
                                  dataset.position.isel(time=3).sel(keypoints="wrist").values)


def test_an_unknown_clip_names_the_stored_ones(db):
    with pytest.raises(UnknownNameError, match="unknown clip 'charlie'; known: alpha, bravo"):
        handdb.load_clip(db, "charlie")
