import numpy as np
import pytest

from handdb.clip import finite_points


@pytest.mark.parametrize("shape", [(50, 21, 2), (50, 21, 3), (7, 2), (0, 3), (4, 0)])
def test_finite_points_are_those_with_every_coordinate_finite(shape):
    points = np.random.default_rng(0).normal(size=shape)
    points.flat[::5] = np.nan
    points.flat[::11] = np.inf
    present = finite_points(points)
    assert present.dtype == bool
    np.testing.assert_array_equal(present, np.isfinite(points).all(axis=-1))
