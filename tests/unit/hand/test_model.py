"""The kinematic hand: 33 degrees of freedom on every skeleton, rigid bones, conventions."""

import numpy as np
import pytest

from handdb.errors import ParameterError, SkeletonError
from handdb.export.rotations import JointMotion, motion_positions
from handdb.hand.anatomy import AXES
from handdb.hand.model import (
    N_DOF,
    build_hand_model,
    clip_to_limits,
    forward_kinematics,
    joint_transforms,
    rotvec_matrices,
)
from handdb.hand.shape import mean_shape
from tests.support.motions import smooth_poses

PRESETS = ("mediapipe21", "dhg22", "thesis21")


def bone_spans(model, positions):
    bones = model.skeleton.bones
    return np.linalg.norm(positions[..., bones[:, 1], :] - positions[..., bones[:, 0], :], axis=-1)


def angle_index(model, name):
    return model.dof_names.index(name)


def test_the_model_has_the_papers_degrees_of_freedom(model):
    per_joint = {}
    for name in model.dof_names[6:]:
        joint = name.split(".")[0]
        per_joint[joint] = per_joint.get(joint, 0) + 1
    assert N_DOF == len(model.dof_names) == 33
    assert per_joint["thumb_cmc"] == per_joint["thumb_mcp"] == 3
    assert per_joint["thumb_ip"] == 1
    for finger in ("index", "middle", "ring", "little"):
        assert per_joint[f"{finger}_mcp"] == 3
        assert per_joint[f"{finger}_pip"] == per_joint[f"{finger}_dip"] == 1
    hinges = [AXES[a] for name, a in zip(model.dof_names[6:], model.dof_axis, strict=True)
              if name.split(".")[0] in ("thumb_ip", "index_pip", "ring_dip")]
    assert set(hinges) == {"flexion"}


@pytest.mark.parametrize("preset", PRESETS)
def test_every_preset_gets_the_same_degrees_of_freedom(preset, model):
    other = build_hand_model(skeleton=preset)
    assert sorted(other.dof_names) == sorted(model.dof_names)
    assert other.skeleton.name == preset


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("hand", ["right", "left"])
def test_every_pose_keeps_the_bone_lengths(preset, hand):
    model = build_hand_model(hand, {"index_pip": 41.5}, skeleton=preset)
    poses = np.random.default_rng(2).uniform(np.maximum(model.lower, -3),
                                             np.minimum(model.upper, 3), (50, N_DOF))
    spans = bone_spans(model, forward_kinematics(model, poses))
    np.testing.assert_allclose(spans, np.broadcast_to(model.bone_lengths, spans.shape))
    assert model.bone_lengths[model.skeleton.bone_names.index("index_pip")] == 41.5


@pytest.mark.parametrize("preset", PRESETS)
def test_the_rest_pose_is_the_hand_shape(preset):
    shape = mean_shape()
    model = build_hand_model(skeleton=preset, shape=shape)
    rest = forward_kinematics(model, model.rest_pose())
    expected = shape.positions(model.skeleton)
    np.testing.assert_allclose(rest - rest[model.skeleton.root],
                               expected - expected[model.skeleton.root], atol=1e-9)


def test_forward_kinematics_vectorises_over_frames_and_particles(model):
    poses = smooth_poses(model, 12, seed=1).reshape(3, 4, N_DOF)
    batched = forward_kinematics(model, poses)
    assert batched.shape == (3, 4, 21, 3)
    np.testing.assert_allclose(batched[2, 1], forward_kinematics(model, poses[2, 1]))


def test_bone_lengths_broadcast_per_candidate(model):
    lengths = model.bone_lengths * np.array([[1.0], [1.2]])
    positions = forward_kinematics(model, model.rest_pose(), lengths)
    np.testing.assert_allclose(bone_spans(model, positions), lengths)


def test_left_hand_is_the_mirror_of_the_right(model):
    left = build_hand_model("left")
    poses = smooth_poses(model, 5, seed=3)
    poses[:, :6] = 0.0
    np.testing.assert_allclose(forward_kinematics(left, poses),
                               forward_kinematics(model, poses) * [-1.0, 1.0, 1.0], atol=1e-12)


@pytest.mark.parametrize("finger", ["index", "middle", "ring", "little"])
@pytest.mark.parametrize("joint", ["mcp", "pip", "dip"])
def test_flexion_bends_fingers_towards_the_palm(model, finger, joint):
    pose = model.rest_pose()
    pose[angle_index(model, f"{finger}_{joint}.flexion")] = np.radians(60)
    tip = model.skeleton.index(f"{finger}_tip")
    rest = forward_kinematics(model, model.rest_pose())
    assert forward_kinematics(model, pose)[tip, 2] > rest[tip, 2] + 5


def test_thumb_flexion_curls_it_across_the_palm(model):
    pose = model.rest_pose()
    for joint in ("cmc", "mcp", "ip"):
        pose[angle_index(model, f"thumb_{joint}.flexion")] = np.radians(45)
    tip = model.skeleton.index("thumb_tip")
    rest = forward_kinematics(model, model.rest_pose())
    bent = forward_kinematics(model, pose)
    assert bent[tip, 0] < rest[tip, 0] - 20  # towards the little finger
    assert bent[tip, 2] > rest[tip, 2]       # and the palm side


def test_positive_abduction_spreads_every_finger_from_the_middle(model):
    rest = forward_kinematics(model, model.rest_pose())
    middle = rest[model.skeleton.index("middle_tip"), 0]
    for finger in ("index", "ring", "little"):
        pose = model.rest_pose()
        pose[angle_index(model, f"{finger}_mcp.abduction")] = np.radians(15)
        tip = model.skeleton.index(f"{finger}_tip")
        spread = forward_kinematics(model, pose)[tip, 0]
        assert abs(spread - middle) > abs(rest[tip, 0] - middle) + 5


def test_bounds_are_the_anatomy_ranges_widened(model):
    wild = np.random.default_rng(4).normal(0.0, 5.0, (100, N_DOF))
    clipped = clip_to_limits(model, wild)
    assert np.all(clipped >= model.lower) and np.all(clipped <= model.upper)
    np.testing.assert_array_equal(clipped[:, :6], wild[:, :6])
    pip = angle_index(model, "index_pip.flexion")
    assert np.degrees(model.upper[pip]) == pytest.approx(110.0 + 20.0)


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("hand", ["right", "left"])
def test_joint_transforms_rebuild_the_joints(preset, hand):
    model = build_hand_model(hand, skeleton=preset)
    poses = smooth_poses(model, 6, seed=5)
    rotations, translations = joint_transforms(model, poses)
    np.testing.assert_allclose(np.linalg.norm(rotations, axis=-1), 1.0)
    rebuilt = motion_positions(JointMotion(rotations, translations), model.skeleton)
    np.testing.assert_allclose(rebuilt, forward_kinematics(model, poses), atol=1e-9)
    finger_bones = [j for j in range(model.n_joints) if model.skeleton.roles[j] in ("pip", "dip")]
    along = translations[:, finger_bones]
    np.testing.assert_allclose(along[..., [0, 2]], 0.0, atol=1e-9)  # +Y along the bone


def test_rotation_vectors_of_zero_and_pi():
    np.testing.assert_allclose(rotvec_matrices(np.zeros(3)), np.eye(3))
    np.testing.assert_allclose(rotvec_matrices(np.array([0.0, 0.0, np.pi])),
                               np.diag([-1.0, -1.0, 1.0]), atol=1e-12)


def test_bad_geometry_is_refused(model):
    with pytest.raises(SkeletonError, match="positive"):
        model.with_geometry(-model.bone_lengths)
    with pytest.raises(SkeletonError, match="not bones"):
        build_hand_model("right", {"wrist": 10.0})
    with pytest.raises(ParameterError, match="hand must be one of left, right"):
        build_hand_model("both")
