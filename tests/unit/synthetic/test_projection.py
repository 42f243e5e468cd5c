"""Orthographic and pinhole projection."""

import numpy as np
import pytest

from handdb.synthetic.projection import project_orthographic, project_pinhole


@pytest.fixture
def points():
    rng = np.random.default_rng(5)
    xyz = rng.uniform(-100.0, 100.0, (7, 21, 3))
    xyz[..., 2] += 300.0
    return xyz


def test_orthographic_is_scale_times_xy_plus_centre(points):
    uv = project_orthographic(points, 2.5, (960.0, 540.0))
    np.testing.assert_allclose(uv[..., 0], 2.5 * points[..., 0] + 960.0)
    np.testing.assert_allclose(uv[..., 1], 2.5 * points[..., 1] + 540.0)


def test_pinhole_matches_the_intrinsic_matrix(points):
    fx, fy, cx, cy = 500.0, 520.0, 960.0, 540.0
    intrinsics = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    homogeneous = points @ intrinsics.T
    expected = homogeneous[..., :2] / homogeneous[..., 2:]
    np.testing.assert_allclose(project_pinhole(points, fx, fy, cx, cy), expected)


def test_pinhole_refuses_points_behind_the_camera(points):
    behind = points.copy()
    behind[0, 0, 2] = -1.0
    with pytest.raises(ValueError, match="not in front of the camera"):
        project_pinhole(behind, 500.0, 500.0, 0.0, 0.0)


def test_orthographic_refuses_a_non_positive_scale(points):
    with pytest.raises(ValueError, match="scale"):
        project_orthographic(points, 0.0)
