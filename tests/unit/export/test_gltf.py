"""glTF export read back with pygltflib: structure, samplers, and the pose it reproduces."""

import numpy as np
import pytest

from handdb.errors import ParameterError, StageError
from handdb.export.gltf import export_clip_gltf
from handdb.export.rotations import CAMERA_TO_Y_UP, joint_rotations, rest_pose, world_transforms
from handdb.hand.skeletons import load_skeleton
from tests.support.gltf_reading import open_gltf
from tests.support.motions import make_hinge_motion

#: float32 positions of a hand in metres: well under a micrometre.
FLOAT32_M = 1e-6


def y_up_m(xyz_mm):
    return 1e-3 * CAMERA_TO_Y_UP.apply(xyz_mm.reshape(-1, 3)).reshape(xyz_mm.shape)


def export(path, motion, **kwargs):
    return export_clip_gltf(path, clip_id="clip-01", skeleton=motion.skeleton, xyz=motion.xyz,
                            bone_lengths=motion.bone_lengths, fps=motion.fps, units="mm",
                            hand="right", **kwargs)


@pytest.fixture(scope="module")
def dhg_clip(dhg_mm, dhg_bone_lengths, tmp_path_factory):
    skeleton = load_skeleton("dhg22")
    path = export_clip_gltf(tmp_path_factory.mktemp("gltf") / "dhg.glb", clip_id="dhg",
                            skeleton=skeleton, xyz=dhg_mm, bone_lengths=dhg_bone_lengths,
                            fps=30.0, units="mm", hand="right")
    return open_gltf(path), skeleton, dhg_bone_lengths


def test_real_capture_structure(dhg_clip):
    clip, skeleton, _ = dhg_clip
    document = clip.document
    names = [node.name for node in document.nodes]
    assert names == [*skeleton.joints, "RightHandMesh", "RightHand"]
    assert clip.skin_joints == list(range(skeleton.n_joints))
    assert document.skins[0].skeleton == skeleton.root
    assert document.nodes[-1].extras == {"handdb:clipId": "dhg", "handdb:hand": "right",
                                         "handdb:units": "mm"}
    assert (document.animations[0].name, document.scenes[0].name) == ("dhg", "dhg")
    assert document.asset.version == "2.0"
    channels = clip.channels()
    assert {node for node, path in channels if path == "rotation"} == set(clip.skin_joints)
    assert (skeleton.root, "translation") in channels
    for times, values in channels.values():
        assert len(times) == len(values) == 95
        assert np.all(np.diff(times) > 0)
        np.testing.assert_allclose(times, np.arange(95) / 30.0, rtol=1e-6)
    for (_, path), (_, values) in channels.items():
        if path == "rotation":
            np.testing.assert_allclose(np.linalg.norm(values, axis=1), 1.0, atol=1e-6)


def test_real_capture_pose_is_reproduced_in_metres(dhg_clip, dhg_mm):
    clip, _, _ = dhg_clip
    np.testing.assert_allclose(clip.joint_world_positions(), y_up_m(dhg_mm), atol=FLOAT32_M)


def test_inverse_bind_matrices_undo_the_rest_pose(dhg_clip):
    clip, skeleton, lengths = dhg_clip
    inverse = clip.accessor(clip.document.skins[0].inverseBindMatrices).reshape(-1, 4, 4)
    inverse = np.swapaxes(inverse, -1, -2)  # column-major in the file
    orientations, positions = world_transforms(rest_pose(skeleton, lengths), skeleton)
    bind = np.tile(np.eye(4), (skeleton.n_joints, 1, 1))
    bind[:, :3, :3], bind[:, :3, 3] = orientations[0], positions[0] * 1e-3
    np.testing.assert_allclose(inverse @ bind, np.tile(np.eye(4), (skeleton.n_joints, 1, 1)),
                               atol=1e-6)


def test_the_skinned_mesh_has_one_influence_set_per_vertex(dhg_clip):
    clip, skeleton, _ = dhg_clip
    primitive = clip.document.meshes[0].primitives[0]
    vertices = clip.accessor(primitive.attributes.POSITION)
    joints = clip.accessor(primitive.attributes.JOINTS_0)
    weights = clip.accessor(primitive.attributes.WEIGHTS_0)
    assert len(vertices) == len(joints) == len(weights) > 1000
    assert joints.max() < skeleton.n_joints
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-6)
    assert clip.accessor(primitive.indices).max() < len(vertices)
    # a hand in metres: 10-30 cm across
    assert 0.1 < np.ptp(vertices, axis=0).max() < 0.3


def test_same_rotations_as_the_usd_export(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=20, seed=3)
    clip = open_gltf(export(tmp_path / "clip.glb", motion))
    expected = joint_rotations(motion.xyz, motion.skeleton, motion.bone_lengths,
                               keep_lengths=False).rotations
    channels = clip.channels()
    for joint in range(motion.skeleton.n_joints):
        if joint == motion.skeleton.root:
            continue  # the root is turned Y-up
        xyzw = channels[joint, "rotation"][1]
        np.testing.assert_allclose(np.abs(np.sum(xyzw * np.roll(expected[:, joint], -1, -1),
                                                 axis=1)), 1.0, atol=1e-6)


def test_keep_lengths_gives_every_bone_its_length(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=10, seed=8)
    noisy = motion.xyz + np.random.default_rng(0).normal(scale=3.0, size=motion.xyz.shape)
    path = export_clip_gltf(tmp_path / "noisy.glb", clip_id="n", skeleton=motion.skeleton,
                            xyz=noisy, bone_lengths=motion.bone_lengths, fps=motion.fps,
                            units="mm", hand="left", keep_lengths=True)
    world = open_gltf(path).joint_world_positions()
    parent, child = motion.skeleton.bones.T
    bones = np.linalg.norm(world[:, child] - world[:, parent], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(1e-3 * motion.bone_lengths[child],
                                                      bones.shape), atol=FLOAT32_M)
    exact = open_gltf(export_clip_gltf(
        tmp_path / "exact.glb", clip_id="n", skeleton=motion.skeleton, xyz=noisy,
        bone_lengths=motion.bone_lengths, fps=motion.fps, units="mm", hand="left"))
    np.testing.assert_allclose(exact.joint_world_positions(), y_up_m(noisy), atol=FLOAT32_M)


def test_missing_joints_and_bad_suffix_are_refused(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=6, seed=1)
    with pytest.raises(ParameterError, match="suffix must be .glb"):
        export(tmp_path / "clip.gltf", motion)
    motion.xyz[2, 4] = np.nan
    with pytest.raises(StageError, match="1 of 6 frames have joints without a 3D position"):
        export(tmp_path / "clip.glb", motion)
    assert list(tmp_path.iterdir()) == []
