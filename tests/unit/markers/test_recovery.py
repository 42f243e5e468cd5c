"""A finger the fit has lost is found again; angles no marker sees follow their neighbours."""

import numpy as np
import pytest

from handdb.hand.model import forward_kinematics
from handdb.markers.solve import (
    carry_unconstrained,
    constrained_dofs,
    fit_pose_lsq,
    fit_pose_recovering,
)

RING = ("ring_mcp.flexion", "ring_pip.flexion", "ring_dip.flexion")


@pytest.fixture(scope="module")
def ring_curled(model):
    """A pose with the ring finger curled 80 degrees at each joint, 400 mm away."""
    pose = model.rest_pose()
    pose[2] = 400.0
    for name in RING:
        pose[model.dof_names.index(name)] = np.radians(80.0)
    return pose


def test_a_finger_started_in_the_wrong_valley_is_fitted_again(model, ring_curled):
    markers = forward_kinematics(model, ring_curled)
    visible = np.ones(model.n_joints, dtype=bool)
    start = ring_curled.copy()
    for name in RING:  # the ring finger bent back as far as it goes: far from its markers
        start[model.dof_names.index(name)] = model.lower[model.dof_names.index(name)]

    def worst(pose):
        return np.linalg.norm(forward_kinematics(model, pose) - markers, axis=-1).max()

    assert worst(fit_pose_lsq(model, markers, visible, start, start)) > 50.0
    assert worst(fit_pose_recovering(model, markers, visible, start, start)) < 0.5


def test_angles_are_constrained_only_by_markers_at_or_beyond_their_bone(model):
    skeleton = model.skeleton
    visible = np.ones((2, model.n_joints), dtype=bool)
    visible[1, skeleton.indices(["ring_pip", "ring_dip", "ring_tip"])] = False
    constrained = constrained_dofs(model, visible)
    assert constrained[0].all()
    names = np.array(model.dof_names)
    ring = np.char.startswith(names, "ring_")
    assert not constrained[1, ring].any()
    assert constrained[1, ~ring].all()
    visible[1, skeleton.index("ring_tip")] = True  # the tip alone constrains the whole ring
    assert constrained_dofs(model, visible)[1, ring].all()


def test_unconstrained_angles_are_interpolated_between_the_frames_that_see_them():
    poses = np.zeros((5, 33))
    poses[:, 10] = [1.0, 9.0, 9.0, 4.0, 9.0]
    constrained = np.ones((5, 33), dtype=bool)
    constrained[[1, 2, 4], 10] = False
    carried = carry_unconstrained(poses, constrained)
    np.testing.assert_allclose(carried[:, 10], [1.0, 2.0, 3.0, 4.0, 4.0])
    np.testing.assert_array_equal(carried[:, :10], poses[:, :10])
    assert poses[1, 10] == 9.0  # the input is left as it is


def test_a_track_marking_too_few_joints_is_refused_with_what_to_do():
    from handdb.errors import ClipDataError
    from handdb.markers.fit import fit_markers

    markers = np.full((5, 21, 3), np.nan)
    markers[:, [4, 8, 12, 16, 20, 6, 10, 14, 18, 3]] = 1.0  # a glove: tips and middles
    with pytest.raises(ClipDataError, match=r"at least 11 of the 21 joints.*marks 10.*joint_map"):
        fit_markers(markers)
