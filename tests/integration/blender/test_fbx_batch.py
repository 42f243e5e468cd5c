"""One Blender process converts a batch of clips to FBX; a clip it cannot convert is named
and the others' files are kept."""

import json
import subprocess

import pytest

from handdb.export.fbx import BLENDER_VARIABLE, FbxConversion, convert_to_fbx, stage_gltf
from handdb.hand.skeletons import load_skeleton
from tests.integration.blender.test_blender_import import BLENDER_PYTHON, IMPORT_SCRIPT
from tests.support.motions import make_hinge_motion

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not BLENDER_PYTHON.exists(),
                       reason=f"no Blender Python at {BLENDER_PYTHON} (make .venv-blender)"),
]


def test_a_batch_converts_every_clip_but_the_broken_one_and_names_it(tmp_path, monkeypatch):
    monkeypatch.setenv(BLENDER_VARIABLE, str(BLENDER_PYTHON))
    skeletons = {"alpha": load_skeleton("mediapipe21"), "charlie": load_skeleton("dhg22")}
    staged = {}
    for seed, (clip_id, skeleton) in enumerate(skeletons.items()):
        motion = make_hinge_motion(skeleton, n_frames=10 + seed, seed=seed)
        staged[clip_id] = stage_gltf(tmp_path, clip_id, clip_id=clip_id, skeleton=skeleton,
                                     xyz=motion.xyz, bone_lengths=motion.bone_lengths,
                                     fps=30.0, units="mm", hand="right")
    (tmp_path / "bravo.glb").write_bytes(b"not a glTF file")
    broken = FbxConversion("bravo", tmp_path / "bravo.glb", tmp_path / "bravo.fbx", 30.0, 10)

    failed = convert_to_fbx([staged["alpha"], broken, staged["charlie"]])

    assert list(failed) == ["bravo"]
    assert "Bad glTF" in failed["bravo"], failed["bravo"]
    assert not broken.target.exists()
    # the last clip's scene holds only its own armature: each conversion starts empty
    run = subprocess.run([str(BLENDER_PYTHON), str(IMPORT_SCRIPT), str(staged["charlie"].target),
                          "0"], capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr[-2000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["armatures"] == 1
    assert sorted(report["bones"]) == sorted(skeletons["charlie"].joints)
    assert report["action_frame_range"] == [0, 10]
    assert report["action"] == "RightHand|charlie"
    assert staged["alpha"].target.is_file()
