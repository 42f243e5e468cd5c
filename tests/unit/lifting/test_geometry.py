import numpy as np
import pytest

from handdb.hand.skeletons import load_skeleton
from handdb.lifting.geometry import (
    accumulate_depths,
    depth_magnitudes,
    eq6_scale,
    path_lists,
    path_matrix,
    projected_lengths,
)


@pytest.fixture
def skeleton():
    return load_skeleton("mediapipe21")


def test_depth_is_the_leg_of_the_bone_triangle():
    # a 5-unit bone seen 6 px long at 2 px per unit spans 3 units of depth
    abs_dz, inconsistency = depth_magnitudes(np.array([[0.0, 6.0]]), np.array([np.nan, 5.0]),
                                             np.array([2.0]))
    assert abs_dz[0, 1] == pytest.approx(4.0)
    assert inconsistency[0, 1] == 0.0


def test_negative_discriminant_is_clamped_and_recorded():
    abs_dz, inconsistency = depth_magnitudes(np.array([[0.0, 14.0]]),
                                             np.array([np.nan, 5.0]), np.array([2.0]))
    assert abs_dz[0, 1] == 0.0
    assert inconsistency[0, 1] == pytest.approx(2.0)   # the track makes the bone 7, not 5


def test_eq6_scale_is_the_largest_ratio(skeleton):
    rng = np.random.default_rng(0)
    uv = rng.normal(size=(3, skeleton.n_joints, 2)) * 40
    lengths = np.full(skeleton.n_joints, 10.0)
    lengths[skeleton.root] = np.nan
    projected = projected_lengths(uv, skeleton)
    scale = eq6_scale(projected, lengths)
    expected = np.max(projected[:, skeleton.bones[:, 1]] / 10.0, axis=1)
    np.testing.assert_allclose(scale, expected)
    abs_dz, inconsistency = depth_magnitudes(projected, lengths, scale)
    # the smallest admissible scale: every bone real, the longest one exactly in plane
    assert np.all(inconsistency[:, skeleton.bones[:, 1]] <= 1e-12)
    np.testing.assert_allclose(np.nanmin(abs_dz, axis=1), 0.0, atol=1e-6)


def test_depths_accumulate_from_the_root(skeleton):
    signed = np.ones((2, skeleton.n_joints))
    z = accumulate_depths(signed, skeleton)
    np.testing.assert_array_equal(z[0], skeleton.depth())


def test_path_lists_walk_each_rows_true_columns_in_order(skeleton):
    on_path = path_matrix(skeleton) > 0
    indices, counts = path_lists(on_path)
    for row in range(len(on_path)):
        np.testing.assert_array_equal(indices[row, : counts[row]], np.flatnonzero(on_path[row]))
