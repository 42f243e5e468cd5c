"""Blender (bpy 4.5, in its own venv ``.venv-blender``) imports the exported USD and glTF."""

import json
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.clip import METERS_PER_UNIT
from handdb.export.bvh import export_clip_bvh
from handdb.export.fbx import BLENDER_VARIABLE, export_clip_fbx
from handdb.export.gltf import export_clip_gltf
from handdb.export.placement import at_origin
from handdb.export.rotations import CAMERA_TO_Y_UP, joint_rotations, motion_positions
from handdb.export.usd import export_clip_usd
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion
from tests.support.paths import REPO

BLENDER_PYTHON = REPO / ".venv-blender" / "bin" / "python"
IMPORT_SCRIPT = Path(__file__).with_name("blender_import.py")

#: Blender's importer turns a Y-up stage to its Z-up world: +90 degrees about x.
Y_UP_TO_BLENDER = Rotation.from_rotvec([np.pi / 2, 0.0, 0.0])

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not BLENDER_PYTHON.exists(),
                       reason=f"no Blender Python at {BLENDER_PYTHON} (make .venv-blender)"),
]


@pytest.mark.parametrize(("suffix", "noise_mm"), [(".usd", 0.0), (".usdz", 2.0)])
def test_blender_imports_an_animated_armature(tmp_path, suffix, noise_mm):
    """Noisy joints (bones that disagree with their lengths) must come through exactly too."""
    hinge = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=40, seed=11)
    motion = replace(hinge, xyz=hinge.xyz + np.random.default_rng(2).normal(
        scale=noise_mm, size=hinge.xyz.shape))
    units = "mm"
    path = export_clip_usd(tmp_path / f"clip{suffix}", clip_id="clip-01", skeleton=motion.skeleton,
                           xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units=units, hand="right")
    frames = [0, 17, len(motion.xyz) - 1]
    run = subprocess.run([str(BLENDER_PYTHON), str(IMPORT_SCRIPT), str(path), *map(str, frames)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])

    assert report["armatures"] == 1
    assert report["bones"] == list(motion.skeleton.joints)
    assert report["action_frame_range"] == [0, len(motion.xyz) - 1]
    assert report["action"] == "clip_01"         # the SkelAnimation, named after the clip
    assert [m["armature_modifier"] for m in report["meshes"]] == [True]

    to_blender = Y_UP_TO_BLENDER * CAMERA_TO_Y_UP
    tolerance = 1e-4 * motion.bone_lengths[motion.bone_lengths > 0].min() * METERS_PER_UNIT[units]
    for frame in frames:
        heads = np.array([report["heads"][str(frame)][joint] for joint in motion.skeleton.joints])
        expected = METERS_PER_UNIT[units] * to_blender.apply(motion.xyz[frame])
        assert np.abs(heads - expected).max() < tolerance


@pytest.mark.parametrize("suffix", [".glb", ".fbx"])
def test_blender_imports_the_gltf_and_fbx_armature_and_animation(tmp_path, monkeypatch,
                                                                 suffix):
    monkeypatch.setenv(BLENDER_VARIABLE, str(BLENDER_PYTHON))
    hinge = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=40, seed=11)
    motion = replace(hinge, fps=60.0, xyz=hinge.xyz + np.random.default_rng(3).normal(
        scale=2.0, size=hinge.xyz.shape))
    export = export_clip_gltf if suffix == ".glb" else export_clip_fbx
    path = export(tmp_path / f"clip{suffix}", clip_id="clip-01", skeleton=motion.skeleton,
                  xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                  units="mm", hand="right")
    frames = [0, 17, len(motion.xyz) - 1]
    run = subprocess.run([str(BLENDER_PYTHON), str(IMPORT_SCRIPT), str(path), *map(str, frames),
                          "--fps", str(motion.fps)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])

    assert report["armatures"] == 1
    assert sorted(report["bones"]) == sorted(motion.skeleton.joints)
    assert report["action_frame_range"] == [0, len(motion.xyz) - 1]
    assert report["action"] == ("clip-01" if suffix == ".glb" else "RightHand|clip-01")
    skinned = [m for m in report["meshes"] if m["armature_modifier"]]
    assert [m["name"] for m in skinned] == ["RightHandMesh"]

    # glTF and FBX are Y-up in metres (FBX in cm, scaled back); Blender turns them Z-up.
    to_blender = Y_UP_TO_BLENDER * CAMERA_TO_Y_UP
    tolerance = 1e-4 * motion.bone_lengths[motion.bone_lengths > 0].min() * 1e-3
    # FBX bones are rigid: the joints the bones reach, keeping their lengths.
    expected = motion.xyz if suffix == ".glb" else motion_positions(joint_rotations(
        motion.xyz, motion.skeleton, motion.bone_lengths, keep_lengths=True), motion.skeleton)
    for frame in frames:
        heads = np.array([report["heads"][str(frame)][joint] for joint in motion.skeleton.joints])
        assert np.abs(heads - 1e-3 * to_blender.apply(expected[frame])).max() < tolerance


def test_blender_imports_the_bvh_at_true_size_with_its_default_scale(tmp_path):
    """BVH is in metres: Blender's importer at scale 1 puts every bone head where it was."""
    motion = make_hinge_motion(load_skeleton("thesis21"), n_frames=30, seed=5)
    units = "cm"
    xyz = motion.xyz / 10.0                                  # the hinge motion is in mm
    path = export_clip_bvh(tmp_path / "clip-01.bvh", skeleton=motion.skeleton, xyz=xyz,
                           bone_lengths=motion.bone_lengths / 10.0, fps=motion.fps, units=units)
    frames = [0, 11, len(xyz) - 1]
    # Blender's BVH importer puts the file's first frame at frame 1 at the earliest.
    run = subprocess.run([str(BLENDER_PYTHON), str(IMPORT_SCRIPT), str(path),
                          *(str(frame + 1) for frame in frames)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["armatures"] == 1
    assert sorted(report["bones"]) == sorted(motion.skeleton.joints)
    assert report["action_frame_range"] == [1, len(xyz)]
    assert report["action"] == "clip-01"                  # the file's name: the clip id
    # Rigid bones: the joints the bones reach keeping their lengths, in metres.
    expected = motion_positions(joint_rotations(xyz, motion.skeleton, motion.bone_lengths / 10.0,
                                                keep_lengths=True), motion.skeleton)
    to_blender = Y_UP_TO_BLENDER * CAMERA_TO_Y_UP
    tolerance = 1e-4 * motion.bone_lengths[motion.bone_lengths > 0].min() * 1e-3
    for frame in frames:
        heads = np.array([report["heads"][str(frame + 1)][joint]
                          for joint in motion.skeleton.joints])
        assert np.abs(heads - METERS_PER_UNIT[units] * to_blender.apply(expected[frame])).max() \
            < tolerance


def test_a_hand_at_the_origin_stands_on_blenders_floor(tmp_path):
    """``at_origin`` seen in Blender (Z up): the wrist of frame 0 above the origin, min z 0."""
    motion = make_hinge_motion(load_skeleton("dhg22"), n_frames=20, seed=3)
    xyz = at_origin(motion.xyz + [80.0, 150.0, 600.0], motion.skeleton)    # camera mm
    path = export_clip_usd(tmp_path / "clip.usd", clip_id="clip-01", skeleton=motion.skeleton,
                           xyz=xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                           units="mm", hand="right")
    frames = list(range(len(xyz)))
    run = subprocess.run([str(BLENDER_PYTHON), str(IMPORT_SCRIPT), str(path), *map(str, frames)],
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    heads = json.loads(run.stdout.strip().splitlines()[-1])["heads"]
    everywhere = np.array([list(heads[str(frame)].values()) for frame in frames])
    root = motion.skeleton.joints[motion.skeleton.root]
    np.testing.assert_allclose(heads["0"][root][:2], 0.0, atol=1e-6)          # metres
    assert everywhere[..., 2].min() == pytest.approx(0.0, abs=1e-6)
    assert heads["0"][root][2] > 0.0
