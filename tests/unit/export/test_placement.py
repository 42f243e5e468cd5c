"""Placing a clip at the origin, on the floor: one translation, the motion unchanged."""

import numpy as np

from handdb.export.placement import at_origin, origin_shift
from handdb.export.rotations import CAMERA_TO_Y_UP
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion


def test_first_placed_root_at_the_origin_and_lowest_point_on_the_floor():
    skeleton = load_skeleton("thesis21")
    xyz = make_hinge_motion(skeleton, n_frames=20, seed=4).xyz + [120.0, -40.0, 650.0]
    xyz[0, skeleton.root] = np.nan           # the root is first placed at frame 1
    xyz[3, 5] = np.nan
    placed = CAMERA_TO_Y_UP.apply(at_origin(xyz, skeleton).reshape(-1, 3)).reshape(xyz.shape)
    np.testing.assert_allclose(placed[1, skeleton.root, [0, 2]], 0.0, atol=1e-9)
    assert abs(placed[1, skeleton.root, 1]) > 1.0        # the wrist is not on the floor
    assert np.nanmin(placed[..., 1]) == 0.0 or abs(np.nanmin(placed[..., 1])) < 1e-9
    assert np.isnan(placed[3, 5]).all() and np.isnan(placed[0, skeleton.root]).all()
    # Every relative position is kept.
    moved = at_origin(xyz, skeleton) - xyz
    np.testing.assert_allclose(np.nanmax(moved, axis=(0, 1)), np.nanmin(moved, axis=(0, 1)))


def test_a_clip_whose_root_is_never_placed_is_unchanged():
    skeleton = load_skeleton("mediapipe21")
    xyz = make_hinge_motion(skeleton, n_frames=5, seed=1).xyz
    xyz[:, skeleton.root] = np.nan
    np.testing.assert_array_equal(origin_shift(xyz, skeleton), np.zeros(3))
