"""The rigid palm's template and poses, recovered from 2D points alone."""

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.lifting.palm_template import (
    fit_template,
    fit_tilts,
    information_ratio,
    on_bone_spheres,
)

#: A right palm, mm, the root first: wrist, four knuckles arched off the plane.
PALM = np.array([[0.0, 0.0, 0.0], [22.0, 82.0, 4.0], [2.0, 84.0, -3.0], [-16.0, 78.0, -1.5],
                 [-32.0, 68.0, 5.0]])
PARENTS = np.array([-1, 0, 0, 0, 0])
LENGTHS = np.r_[np.nan, np.linalg.norm(PALM[1:], axis=1)]


def seen(template, rotations, scale=1.7):
    """Scaled orthographic image points of the template in each pose, pixels."""
    return scale * np.einsum("tij,kj->tki", rotations, template)[..., :2]


def turning_views(n_frames=120, seed=0):
    rng = np.random.default_rng(seed)
    start = Rotation.from_euler("x", 150, degrees=True)
    wobble = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.05, (n_frames, 3)), axis=0))
    return (wobble * start).as_matrix()


def pairwise(points):
    return np.linalg.norm(points[:, None] - points[None], axis=-1)


def test_the_better_pose_of_each_frame_reproduces_its_view():
    rotations = turning_views()
    tilts = fit_tilts(seen(PALM, rotations), PALM)
    np.testing.assert_allclose(tilts.residual[:, 0], 0.0, atol=1e-6)
    np.testing.assert_allclose(tilts.scale[:, 0], 1.7, rtol=1e-6)
    depth = np.einsum("tij,kj->tki", tilts.rotation[:, 0], PALM)[..., 2]
    np.testing.assert_allclose(depth, np.einsum("tij,kj->tki", rotations, PALM)[..., 2],
                               atol=1e-5)
    assert np.all(tilts.residual[:, 1] >= tilts.residual[:, 0])


def test_a_planar_palm_fits_both_tilts_exactly():
    flat = PALM * [1.0, 1.0, 0.0]
    tilts = fit_tilts(seen(flat, turning_views(20)), flat)
    np.testing.assert_allclose(tilts.residual, 0.0, atol=1e-6)


def test_the_template_is_recovered_from_the_track_alone():
    points = seen(PALM, turning_views())
    rng = np.random.default_rng(1)
    start = on_bone_spheres(PALM + rng.normal(0, 4.0, PALM.shape), PARENTS, LENGTHS)
    template = fit_template(points, start, PARENTS, LENGTHS)
    np.testing.assert_allclose(pairwise(template), pairwise(PALM), atol=0.05)
    np.testing.assert_allclose(np.linalg.norm(template[1:], axis=1), LENGTHS[1:])


def test_frames_missing_palm_joints_have_no_pose():
    points = seen(PALM, turning_views(5))
    points[2, 1:3] = np.nan
    points[3, 1:4] = np.nan
    tilts = fit_tilts(points, PALM)
    assert np.isfinite(tilts.residual[2]).all() and np.isnan(tilts.residual[3]).all()


def test_a_still_view_carries_no_depth_information():
    still = np.repeat(turning_views(1), 50, axis=0)
    assert information_ratio(still, np.full(50, 1.7)) < 1e-12
    assert information_ratio(turning_views(), np.full(120, 1.7)) > 0.01
