import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom, UsdSkel

from handdb.clip import METERS_PER_UNIT
from handdb.errors import StageError
from handdb.export.mesh import hand_mesh, posed_vertices
from handdb.export.rotations import CAMERA_TO_Y_UP, rest_pose, rest_positions
from handdb.export.usd import animation_name, export_clip_usd, joint_paths
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion
from tests.support.usd_reading import joint_world_positions, open_skeleton, validation_errors

SUFFIXES = [".usd", ".usdc", ".usda", ".usdz"]
MAGIC = {".usd": b"PXR-USDC", ".usdc": b"PXR-USDC", ".usda": b"#usda", ".usdz": b"PK"}


def export(motion, path, **overrides):
    arguments = dict(clip_id="clip-01", skeleton=motion.skeleton, xyz=motion.xyz,
                     bone_lengths=motion.bone_lengths, fps=motion.fps, units="mm", hand="right")
    return export_clip_usd(path, **(arguments | overrides))


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_usdskel_reproduces_the_joints_at_every_frame(hinge_motion, tmp_path, suffix):
    path = export(hinge_motion, tmp_path / f"clip{suffix}")
    assert path.read_bytes().startswith(MAGIC[suffix])
    clip = open_skeleton(path)
    stage_xyz = joint_world_positions(clip, len(hinge_motion.xyz))
    camera_xyz = CAMERA_TO_Y_UP.inv().apply(stage_xyz.reshape(-1, 3)).reshape(stage_xyz.shape)
    tolerance = 1e-4 * hinge_motion.bone_lengths[hinge_motion.bone_lengths > 0].min()
    assert np.abs(camera_xyz - hinge_motion.xyz).max() < tolerance


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_every_registered_validator_passes(mediapipe_motion, tmp_path, suffix):
    clip = open_skeleton(export(mediapipe_motion, tmp_path / f"clip{suffix}"))
    assert validation_errors(clip.stage) == []


@pytest.mark.parametrize(("units", "fps"),
                         [("mm", 30.0), ("cm", 120.0), ("m", 24.0), ("in", 59.94)])
def test_stage_metadata(mediapipe_motion, tmp_path, units, fps):
    path = export(mediapipe_motion, tmp_path / "clip.usda", units=units, fps=fps)
    stage = open_skeleton(path).stage
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y
    assert UsdGeom.GetStageMetersPerUnit(stage) == METERS_PER_UNIT[units]
    assert stage.GetTimeCodesPerSecond() == fps
    assert stage.GetStartTimeCode() == 0
    assert stage.GetEndTimeCode() == len(mediapipe_motion.xyz) - 1
    assert stage.GetDefaultPrim().GetCustomDataByKey("handdb:clipId") == "clip-01"


def test_skeleton_and_animation_layout(mediapipe_motion, tmp_path):
    skeleton = mediapipe_motion.skeleton
    clip = open_skeleton(export(mediapipe_motion, tmp_path / "clip.usdc"))
    stage, skel = clip.stage, clip.skel_query.GetSkeleton()
    joints = list(skel.GetJointsAttr().Get())
    assert joints == joint_paths(skeleton)
    for i, path in enumerate(joints):
        parent = path.rpartition("/")[0]
        assert parent == "" or joints.index(parent) < i
    assert [p.rpartition("/")[2] for p in joints] == list(skeleton.joints)
    assert len(skel.GetBindTransformsAttr().Get()) == len(skel.GetRestTransformsAttr().Get()) == 21
    anim = UsdSkel.Animation(stage.GetPrimAtPath("/RightHand/clip_01"))
    source = UsdSkel.BindingAPI(skel.GetPrim()).GetAnimationSourceRel()
    assert source.GetTargets() == [anim.GetPath()]
    frames = list(range(len(mediapipe_motion.xyz)))
    for attribute in (anim.GetRotationsAttr(), anim.GetTranslationsAttr()):
        assert attribute.GetTimeSamples() == frames
        assert len(attribute.Get(frames[-1])) == skeleton.n_joints
    scales = anim.GetScalesAttr()
    assert scales.GetTimeSamples() == []
    np.testing.assert_array_equal(np.array(scales.Get(frames[-1])), np.ones((21, 3)))


def test_a_constant_channel_is_written_once(mediapipe_motion, tmp_path):
    """A hand that keeps its bone lengths and does not move has the same translations at
    every frame: they are the attribute's default, and UsdSkel still poses every frame."""
    skeleton, lengths = mediapipe_motion.skeleton, mediapipe_motion.bone_lengths
    xyz = mediapipe_motion.xyz - mediapipe_motion.xyz[:, [skeleton.root]]
    path = export(mediapipe_motion, tmp_path / "c.usda", xyz=xyz, keep_lengths=True)
    clip = open_skeleton(path)
    anim = UsdSkel.Animation(clip.stage.GetPrimAtPath("/RightHand/clip_01"))
    assert anim.GetTranslationsAttr().GetTimeSamples() == []
    assert len(anim.GetRotationsAttr().GetTimeSamples()) == len(xyz)
    stage_xyz = joint_world_positions(clip, len(xyz))
    camera_xyz = CAMERA_TO_Y_UP.inv().apply(stage_xyz.reshape(-1, 3)).reshape(stage_xyz.shape)
    bones = camera_xyz[:, skeleton.bones[:, 1]] - camera_xyz[:, skeleton.bones[:, 0]]
    np.testing.assert_allclose(np.linalg.norm(bones, axis=-1),
                               np.broadcast_to(lengths[skeleton.bones[:, 1]], bones.shape[:2]),
                               rtol=1e-5)
    np.testing.assert_allclose(camera_xyz[:, skeleton.root], 0.0, atol=1e-4)


def test_mesh_skinning_matches_the_posed_hand(mediapipe_motion, tmp_path):
    skeleton, lengths = mediapipe_motion.skeleton, mediapipe_motion.bone_lengths
    clip = open_skeleton(export(mediapipe_motion, tmp_path / "c.usda"))
    skel_query, skinning_query = clip.skel_query, clip.skinning_query
    binding = UsdSkel.BindingAPI(clip.stage.GetPrimAtPath("/RightHand/Mesh"))
    assert binding.GetSkeletonRel().GetTargets() == [skel_query.GetSkeleton().GetPath()]
    indices = np.array(binding.GetJointIndicesPrimvar().Get()).reshape(-1, 2)
    weights = np.array(binding.GetJointWeightsPrimvar().Get()).reshape(-1, 2)
    assert binding.GetJointIndicesPrimvar().GetElementSize() == 2
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-6)
    assert 0 <= indices.min() and indices.max() < skeleton.n_joints

    frame = 17
    points = UsdGeom.Mesh(binding.GetPrim()).GetPointsAttr().Get()
    skinning = skel_query.ComputeSkinningTransforms(frame)
    assert skinning_query.ComputeSkinnedPoints(skinning, points, frame)
    expected = posed_vertices(hand_mesh(skeleton, lengths), mediapipe_motion.xyz[[frame]],
                              skeleton, lengths)[0]
    np.testing.assert_allclose(np.array(points), CAMERA_TO_Y_UP.apply(expected), atol=1e-3)


def test_given_rotations_are_exported(mediapipe_motion, tmp_path):
    skeleton, lengths = mediapipe_motion.skeleton, mediapipe_motion.bone_lengths
    still = rest_pose(skeleton, lengths)
    path = export(mediapipe_motion, tmp_path / "c.usdc", xyz=mediapipe_motion.xyz[:1],
                  rotations=still)
    clip = open_skeleton(path)
    np.testing.assert_allclose(joint_world_positions(clip, 1)[0],
                               CAMERA_TO_Y_UP.apply(rest_positions(skeleton, lengths)), atol=1e-4)


def test_left_hand_and_reexport_over_an_existing_file(tmp_path):
    motion = make_hinge_motion(load_skeleton("thesis21"), n_frames=5)
    path = tmp_path / "c.usd"
    export(motion, path, hand="right")
    export(motion, path, hand="left")
    stage = Usd.Stage.Open(str(path))
    assert stage.GetDefaultPrim().GetPath() == "/LeftHand"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.usd"]


def test_only_the_frames_that_place_every_joint_are_keyed(mediapipe_motion, tmp_path):
    """Empty first and last frames (a detector saw nothing) leave the observed span keyed:
    USD holds its end poses outside it and bridges a frame inside it that lacks a joint."""
    xyz = mediapipe_motion.xyz.copy()
    xyz[:2] = np.nan
    xyz[-3:] = np.nan
    xyz[20, 7] = np.nan
    clip = open_skeleton(export(mediapipe_motion, tmp_path / "c.usda", xyz=xyz))
    keyed = [f for f in range(2, 37) if f != 20]
    anim = UsdSkel.Animation(clip.stage.GetPrimAtPath("/RightHand/clip_01"))
    assert anim.GetRotationsAttr().GetTimeSamples() == keyed
    assert anim.GetTranslationsAttr().GetTimeSamples() == keyed
    assert (clip.stage.GetStartTimeCode(), clip.stage.GetEndTimeCode()) == (2, 36)
    assert validation_errors(clip.stage) == []
    stage_xyz = joint_world_positions(clip, len(xyz))
    camera_xyz = CAMERA_TO_Y_UP.inv().apply(stage_xyz.reshape(-1, 3)).reshape(stage_xyz.shape)
    tolerance = 1e-4 * mediapipe_motion.bone_lengths[mediapipe_motion.bone_lengths > 0].min()
    assert np.abs(camera_xyz[keyed] - xyz[keyed]).max() < tolerance
    np.testing.assert_allclose(camera_xyz[:2], camera_xyz[[2, 2]], atol=1e-9)
    np.testing.assert_allclose(camera_xyz[-3:], camera_xyz[[36] * 3], atol=1e-9)
    between = np.linalg.norm(camera_xyz[20] - xyz[[19, 21]].mean(axis=0), axis=-1)
    assert between.max() < np.linalg.norm(xyz[21] - xyz[19], axis=-1).max()


def test_missing_positions_and_bad_arguments_are_refused(mediapipe_motion, tmp_path):
    xyz = mediapipe_motion.xyz.copy()
    xyz[:, 7] = np.nan
    with pytest.raises(StageError, match="none of its 40 frames places every joint"):
        export(mediapipe_motion, tmp_path / "c.usd", xyz=xyz)
    with pytest.raises(ValueError, match="suffix"):
        export(mediapipe_motion, tmp_path / "c.fbx")
    with pytest.raises(ValueError, match="units"):
        export(mediapipe_motion, tmp_path / "c.usd", units="ft")
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(("clip_id", "name"), [
    ("clip-01", "clip_01"), ("rapid.s01 take 2", "rapid_s01_take_2"), ("01", "_01"),
    ("Mesh", "Mesh_Animation"), ("", "_"), ("prise-é", "prise__")])
def test_the_animation_is_named_after_the_clip(clip_id, name):
    assert animation_name(clip_id) == name
    assert Sdf.Path.IsValidIdentifier(name)
