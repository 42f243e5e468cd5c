import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.errors import BoneLengthError
from handdb.export.rotations import (
    joint_rotations,
    motion_positions,
    rest_pose,
    rest_positions,
)
from handdb.hand.skeletons import bone_length_array, load_skeleton
from tests.support.motions import make_hinge_motion


def same_rotation(q1, q2):
    """|<q1, q2>| = 1 for equal rotations (either quaternion sign)."""
    return np.abs(np.abs(np.sum(q1 * q2, axis=-1)) - 1.0)


def test_forward_kinematics_reproduces_positions(hinge_motion):
    motion = joint_rotations(hinge_motion.xyz, hinge_motion.skeleton, hinge_motion.bone_lengths)
    assert motion.rotations.shape == (*hinge_motion.xyz.shape[:2], 4)
    np.testing.assert_allclose(np.linalg.norm(motion.rotations, axis=-1), 1.0, atol=1e-12)
    fk = motion_positions(motion, hinge_motion.skeleton)
    np.testing.assert_allclose(fk, hinge_motion.xyz, atol=1e-9)
    np.testing.assert_array_equal(motion.root_translation(hinge_motion.skeleton),
                                  hinge_motion.xyz[:, hinge_motion.skeleton.root])


def test_recovers_the_generating_rotations(hinge_motion):
    motion = joint_rotations(hinge_motion.xyz, hinge_motion.skeleton, hinge_motion.bone_lengths)
    assert same_rotation(motion.rotations, hinge_motion.rotations).max() < 1e-9


@pytest.mark.parametrize("role", ["pip", "dip", "ip"])
def test_hinges_turn_about_their_local_x_only(mediapipe_motion, role):
    skeleton = mediapipe_motion.skeleton
    motion = joint_rotations(mediapipe_motion.xyz, skeleton, mediapipe_motion.bone_lengths)
    hinges = [j for j, r in enumerate(skeleton.roles) if r == role]
    rotvec = Rotation.from_quat(motion.rotations[:, hinges].reshape(-1, 4),
                                scalar_first=True).as_rotvec()
    assert np.abs(rotvec[:, 1:]).max() < 1e-9
    assert np.rad2deg(rotvec[:, 0]).min() > 14.0


def test_no_spin_when_a_finger_straightens():
    skeleton = load_skeleton("mediapipe21")
    hinge = make_hinge_motion(skeleton, n_frames=400, flexion_range=(-3.0, 40.0))
    motion = joint_rotations(hinge.xyz, skeleton, hinge.bone_lengths)
    step = Rotation.from_quat(motion.rotations[1:].reshape(-1, 4), scalar_first=True) * \
        Rotation.from_quat(motion.rotations[:-1].reshape(-1, 4), scalar_first=True).inv()
    generated = Rotation.from_quat(hinge.rotations[1:].reshape(-1, 4), scalar_first=True) * \
        Rotation.from_quat(hinge.rotations[:-1].reshape(-1, 4), scalar_first=True).inv()
    assert np.rad2deg(step.magnitude()).max() < 2 * np.rad2deg(generated.magnitude()).max()
    assert np.all(np.sum(motion.rotations[1:] * motion.rotations[:-1], axis=-1) > 0)


def test_noisy_positions_keep_bone_directions():
    skeleton = load_skeleton("mediapipe21")
    hinge = make_hinge_motion(skeleton, n_frames=20)
    noisy = hinge.xyz + np.random.default_rng(1).normal(scale=2.0, size=hinge.xyz.shape)
    fk = motion_positions(joint_rotations(noisy, skeleton, hinge.bone_lengths), skeleton)
    parent, child = skeleton.bones.T
    fk_bones = fk[:, child] - fk[:, parent]
    noisy_bones = noisy[:, child] - noisy[:, parent]
    np.testing.assert_allclose(np.linalg.norm(fk_bones, axis=-1),
                               np.broadcast_to(hinge.bone_lengths[child], fk_bones.shape[:2]))
    cosine = np.sum(fk_bones * noisy_bones, axis=-1) / (
        np.linalg.norm(fk_bones, axis=-1) * np.linalg.norm(noisy_bones, axis=-1))
    np.testing.assert_allclose(cosine, 1.0, atol=1e-12)
    stretched = joint_rotations(noisy, skeleton, hinge.bone_lengths, keep_lengths=False)
    np.testing.assert_allclose(motion_positions(stretched, skeleton), noisy, atol=1e-9)


@pytest.mark.parametrize("name", ["mediapipe21", "thesis21", "dhg22"])
def test_rest_pose_is_the_average_hand_along_y(name):
    skeleton = load_skeleton(name)
    lengths = make_hinge_motion(skeleton, n_frames=2).bone_lengths
    positions = rest_positions(skeleton, lengths)
    pose = rest_pose(skeleton, lengths)
    np.testing.assert_allclose(motion_positions(pose, skeleton)[0], positions, atol=1e-12)
    np.testing.assert_allclose(pose.rotations[0, skeleton.root], [1, 0, 0, 0], atol=1e-12)
    parent, child = skeleton.bones.T
    np.testing.assert_allclose(np.linalg.norm(positions[child] - positions[parent], axis=1),
                               lengths[child])
    middle = np.diff(positions[skeleton.finger_chain("middle")], axis=0)
    middle /= np.linalg.norm(middle, axis=1, keepdims=True)
    np.testing.assert_allclose(middle @ middle[-1], 1.0)  # a straight finger
    tips = [j for j, (r, f) in enumerate(zip(skeleton.roles, skeleton.fingers, strict=True))
            if r == "tip" and f != "thumb"]
    assert np.all(positions[tips, 1] > 0)
    assert positions[skeleton.index("thumb_tip"), 0] > positions[skeleton.index("index_tip"), 0]


def test_nan_positions_are_refused():
    skeleton = load_skeleton("mediapipe21")
    hinge = make_hinge_motion(skeleton, n_frames=3)
    xyz = hinge.xyz.copy()
    xyz[1, 5] = np.nan
    with pytest.raises(ValueError, match="fill gaps"):
        joint_rotations(xyz, skeleton, hinge.bone_lengths)


def test_bone_length_array_names_the_missing_bone():
    skeleton = load_skeleton("mediapipe21")
    lengths = {bone: 10.0 for bone in skeleton.bone_names}
    array = bone_length_array(skeleton, lengths, complete=True)
    assert np.isnan(array[skeleton.root]) and np.all(np.delete(array, skeleton.root) == 10.0)
    del lengths["index_dip"]
    assert np.isnan(bone_length_array(skeleton, lengths)[skeleton.index("index_dip")])
    with pytest.raises(BoneLengthError, match="index_dip"):
        bone_length_array(skeleton, lengths, complete=True)
