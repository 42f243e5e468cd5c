"""Export the real, noisy DHG capture: bone lengths never match, directions must be kept."""


import numpy as np
import pytest

from handdb.export.mesh import hand_mesh, posed_vertices
from handdb.export.rotations import joint_rotations, motion_positions
from handdb.export.usd import export_clip_usd
from handdb.hand.skeletons import load_skeleton
from tests.support.axes import y_up
from tests.support.usd_reading import joint_world_positions, open_skeleton, validation_errors


@pytest.fixture(scope="module")
def capture(dhg_mm):
    skeleton = load_skeleton("dhg22")
    xyz = dhg_mm
    parent, child = skeleton.bones.T
    lengths = np.zeros(skeleton.n_joints)
    lengths[child] = np.median(np.linalg.norm(xyz[:, child] - xyz[:, parent], axis=-1), axis=0)
    return skeleton, xyz, lengths


def test_noisy_bones_keep_their_directions(capture):
    skeleton, xyz, lengths = capture
    motion = joint_rotations(xyz, skeleton, lengths)
    assert np.isfinite(motion.rotations).all()
    fk = motion_positions(motion, skeleton)
    parent, child = skeleton.bones.T
    measured, posed = xyz[:, child] - xyz[:, parent], fk[:, child] - fk[:, parent]
    np.testing.assert_allclose(np.linalg.norm(posed, axis=-1),
                               np.broadcast_to(lengths[child], posed.shape[:2]))
    cosine = np.sum(measured * posed, axis=-1) / np.linalg.norm(measured, axis=-1) / \
        np.linalg.norm(posed, axis=-1)
    np.testing.assert_allclose(cosine, 1.0, atol=1e-12)
    assert np.abs(fk - xyz).max() > 1.0        # the capture really disagrees with its lengths


@pytest.mark.parametrize("keep_lengths", [False, True])
def test_noisy_capture_exports_valid_usd(capture, tmp_path, keep_lengths):
    skeleton, xyz, lengths = capture
    path = export_clip_usd(tmp_path / "dhg.usda", clip_id="dhg", skeleton=skeleton, xyz=xyz,
                           bone_lengths=lengths, fps=30.0, units="mm", hand="right",
                           keep_lengths=keep_lengths)
    opened = open_skeleton(path)
    assert validation_errors(opened.stage) == []
    rigid = motion_positions(joint_rotations(xyz, skeleton, lengths), skeleton)
    expected = rigid if keep_lengths else xyz
    stage_xyz = joint_world_positions(opened, len(xyz))
    expected = y_up(expected)
    assert np.abs(stage_xyz - expected).max() < 1e-4 * lengths[lengths > 0].min()
    assert np.isfinite(posed_vertices(hand_mesh(skeleton, lengths), xyz, skeleton, lengths)).all()
