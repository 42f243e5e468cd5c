import numpy as np
import pytest

from handdb.export.rotations import motion_positions
from handdb.hand.model import forward_kinematics
from handdb.markers.fit import (
    ROOT_AXES,
    fit_markers,
    fit_positions,
    joint_angles_table,
    joint_motion,
    key_frames,
)
from handdb.store.tables import schema
from tests.support.motions import noisy_markers, smooth_poses


@pytest.fixture(scope="module")
def template_palm(model, true_model):
    """The true hand's bone lengths on the template's palm: what given lengths describe."""
    return model.with_geometry(true_model.bone_lengths)


@pytest.fixture(scope="module")
def capture(template_palm):
    poses = smooth_poses(template_palm, 24, seed=31)
    truth = forward_kinematics(template_palm, poses) / 10.0
    markers = noisy_markers(truth, noise=0.05, missing_share=0.25, seed=9)
    return truth, markers


@pytest.fixture(scope="module")
def fit(template_palm, capture):
    lengths = dict(zip(template_palm.skeleton.bone_names, template_palm.bone_lengths / 10.0,
                       strict=True))
    return fit_markers(capture[1], units="cm", bone_lengths=lengths, key_step=3)


def test_key_frames_cover_both_ends():
    np.testing.assert_array_equal(key_frames(10, 4), [0, 4, 8, 9])
    np.testing.assert_array_equal(key_frames(3, 1), [0, 1, 2])


def test_fit_reproduces_the_joints_in_clip_units(capture, fit):
    truth, markers = capture
    errors = np.linalg.norm(fit.joints - truth, axis=-1)
    assert fit.calibration is None
    assert errors.mean() < 0.12
    visible = np.isfinite(markers).all(axis=-1)
    np.testing.assert_array_equal(np.isfinite(fit.residual), visible)
    assert np.nanmean(fit.residual) < 0.1


def test_joint_angles_rows_name_joint_and_axis(fit):
    table = joint_angles_table("m01", fit.model, fit.poses)
    assert table.schema.equals(schema("joint_angles"))
    n_frames = len(fit.poses)
    assert table.num_rows == n_frames * 30
    first = table.slice(0, 30).to_pydict()
    pairs = set(zip(first["joint"], first["axis"], strict=True))
    assert ("index_pip", "flexion") in pairs and ("thumb_cmc", "twist") in pairs
    assert {("wrist", axis) for axis in ROOT_AXES} <= pairs
    flexion = [a for j, ax, a in zip(first["joint"], first["axis"], first["angle_deg"],
                                     strict=True) if (j, ax) == ("index_pip", "flexion")][0]
    index = fit.model.dof_names.index("index_pip.flexion")
    assert flexion == pytest.approx(np.degrees(fit.poses[0, index]))


def test_fit_positions_are_the_fitted_joints(fit):
    positions = fit_positions(fit)
    assert positions.method == "marker-fit"
    np.testing.assert_array_equal(positions.xyz, fit.joints)
    assert np.isnan(positions.sign_confidence).all() and np.isnan(positions.scale).all()


@pytest.mark.slow
def test_fit_without_bone_lengths_calibrates_them(true_model):
    poses = smooth_poses(true_model, 16, seed=32)
    truth = forward_kinematics(true_model, poses)
    markers = noisy_markers(truth, noise=0.5, missing_share=0.2, seed=10)
    fitted = fit_markers(markers, key_step=2)
    assert fitted.calibration is not None
    assert np.abs(fitted.model.bone_lengths - true_model.bone_lengths).max() < 1.5
    assert np.linalg.norm(fitted.joints - truth, axis=-1).mean() < 1.5


def test_joint_motion_rebuilds_the_fitted_joints(fit):
    motion = joint_motion(fit, units="cm")
    assert motion.rotations.shape == fit.joints.shape[:2] + (4,)
    np.testing.assert_allclose(motion_positions(motion, fit.model.skeleton), fit.joints,
                               atol=1e-9)
    dots = np.sum(motion.rotations[1:] * motion.rotations[:-1], axis=-1)
    assert np.all(dots >= 0.0)
