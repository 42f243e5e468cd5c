import numpy as np
import pytest

from handdb.errors import SkeletonError
from handdb.hand.model import (
    AXES,
    N_DOF,
    build_hand_model,
    clip_to_limits,
    forward_kinematics,
    local_quaternions,
    rest_offsets,
    rotvec_matrices,
)

from .conftest import smooth_poses


def bone_spans(model, positions):
    bones = model.skeleton.bones
    return np.linalg.norm(positions[..., bones[:, 1], :] - positions[..., bones[:, 0], :], axis=-1)


def quaternion_matrices(wxyz):
    w, x, y, z = np.moveaxis(wxyz, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def test_the_model_has_the_papers_degrees_of_freedom(model):
    joints = np.asarray(model.skeleton.joints)[model.dof_joint]
    per_joint = {name: int((joints == name).sum()) for name in set(joints)}
    assert N_DOF == 6 + len(model.dof_joint) == 33
    assert per_joint["thumb_cmc"] == per_joint["thumb_mcp"] == 3
    assert per_joint["thumb_ip"] == 1
    for finger in ("index", "middle", "ring", "little"):
        assert per_joint[f"{finger}_mcp"] == 3
        assert per_joint[f"{finger}_pip"] == per_joint[f"{finger}_dip"] == 1
    hinges = model.dof_axis[np.isin(joints, ["thumb_ip", "index_pip", "ring_dip"])]
    assert set(AXES[a] for a in hinges) == {"flexion"}


def test_forward_kinematics_vectorises_over_frames_and_particles(model):
    poses = smooth_poses(model, 12, seed=1).reshape(3, 4, N_DOF)
    batched = forward_kinematics(model, poses)
    assert batched.shape == (3, 4, 21, 3)
    one = forward_kinematics(model, poses[2, 1])
    np.testing.assert_allclose(batched[2, 1], one)


@pytest.mark.parametrize("hand", ["right", "left"])
def test_every_pose_keeps_the_bone_lengths(hand):
    model = build_hand_model(hand, {"index_pip": 41.5})
    poses = np.random.default_rng(2).uniform(np.maximum(model.lower, -3),
                                             np.minimum(model.upper, 3), (50, N_DOF))
    spans = bone_spans(model, forward_kinematics(model, poses))
    np.testing.assert_allclose(spans, np.broadcast_to(model.bone_lengths, spans.shape))
    assert model.bone_lengths[model.skeleton.bone_names.index("index_pip")] == 41.5


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


def test_flexion_bends_fingers_towards_the_palm(model):
    pose = model.rest_pose()
    flexion = [k for k, (j, a) in enumerate(zip(model.dof_joint, model.dof_axis, strict=True))
               if model.skeleton.joints[j] == "index_pip" and AXES[a] == "flexion"][0]
    pose[6 + flexion] = np.radians(60)
    tip = model.skeleton.index("index_tip")
    rest = forward_kinematics(model, model.rest_pose())
    assert forward_kinematics(model, pose)[tip, 2] > rest[tip, 2] + 10


def test_clipping_respects_the_joint_limits(model):
    wild = np.random.default_rng(4).normal(0.0, 5.0, (100, N_DOF))
    clipped = clip_to_limits(model, wild)
    assert np.all(clipped >= model.lower) and np.all(clipped <= model.upper)
    np.testing.assert_array_equal(clipped[:, :6], wild[:, :6])
    assert np.all(model.lower[6:] < 0) and np.all(model.upper[6:] > 0)


def test_local_quaternions_and_rest_offsets_rebuild_the_joints(model):
    poses = smooth_poses(model, 6, seed=5)
    rotations = quaternion_matrices(local_quaternions(model, poses))
    np.testing.assert_allclose(np.linalg.norm(local_quaternions(model, poses), axis=-1), 1.0)
    offsets = rest_offsets(model)
    world = np.empty_like(rotations)
    positions = np.empty(poses.shape[:1] + (model.n_joints, 3))
    for j, parent in enumerate(model.skeleton.parents):
        if parent < 0:
            world[:, j] = rotations[:, j]
            positions[:, j] = poses[:, :3]
        else:
            world[:, j] = world[:, parent] @ rotations[:, j]
            positions[:, j] = positions[:, parent] + world[:, parent] @ offsets[j]
    np.testing.assert_allclose(positions, forward_kinematics(model, poses), atol=1e-9)


def test_rotation_vectors_of_zero_and_pi():
    np.testing.assert_allclose(rotvec_matrices(np.zeros(3)), np.eye(3))
    np.testing.assert_allclose(rotvec_matrices(np.array([0.0, 0.0, np.pi])),
                               np.diag([-1.0, -1.0, 1.0]), atol=1e-12)


def test_bad_geometry_is_refused(model):
    with pytest.raises(SkeletonError, match="positive"):
        model.with_geometry(-model.bone_lengths)
    with pytest.raises(SkeletonError, match="not bones"):
        build_hand_model("right", {"wrist": 10.0})
    with pytest.raises(SkeletonError, match="right' or 'left"):
        build_hand_model("both")
