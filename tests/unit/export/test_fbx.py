"""FBX export finds Blender, or says exactly how to get it (the conversion itself is tested
with Blender in tests/integration/blender)."""

import sys

import pytest
from typer.testing import CliRunner

from handdb.cli import app
from handdb.errors import MissingToolError, ParameterError
from handdb.export import fbx
from handdb.export.fbx import BLENDER_VARIABLE, blender_command, export_clip_fbx
from handdb.hand.skeletons import load_skeleton
from tests.integration.cli.test_export_cli import write_database
from tests.support.motions import make_hinge_motion


@pytest.fixture
def no_blender(monkeypatch, tmp_path):
    monkeypatch.delenv(BLENDER_VARIABLE, raising=False)
    monkeypatch.setenv("PATH", str(tmp_path / "empty-bin"))


def test_without_blender_the_error_says_how_to_get_it(no_blender, tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=4, seed=1)
    with pytest.raises(MissingToolError, match="blender.org.*pip install bpy.*--format glb"):
        export_clip_fbx(tmp_path / "clip.fbx", clip_id="c", skeleton=motion.skeleton,
                        xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=30.0,
                        units="mm", hand="right")
    assert list(tmp_path.iterdir()) == []


def test_a_blender_variable_naming_no_file_is_refused(monkeypatch, tmp_path):
    monkeypatch.setenv(BLENDER_VARIABLE, str(tmp_path / "blender"))
    with pytest.raises(MissingToolError, match=f"{BLENDER_VARIABLE}=.*blender is not a file"):
        blender_command()


@pytest.mark.parametrize(("name", "expected"), [
    ("python3.11", []),
    ("blender", ["--background", "--factory-startup", "--python-exit-code", "1", "--python"]),
])
def test_blender_runs_as_its_python_or_its_executable(monkeypatch, tmp_path, name, expected):
    program = tmp_path / name
    program.write_text("")
    monkeypatch.setenv(BLENDER_VARIABLE, str(program))
    assert blender_command() == [str(program), *expected]


def test_blender_on_the_path_is_found(monkeypatch, tmp_path):
    monkeypatch.delenv(BLENDER_VARIABLE, raising=False)
    program = tmp_path / "blender"
    program.write_text("#!/bin/sh\n")
    program.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert blender_command()[0] == str(program)


def test_the_suffix_is_checked_first(no_blender, tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=4, seed=1)
    with pytest.raises(ParameterError, match="suffix must be .fbx"):
        export_clip_fbx(tmp_path / "clip.glb", clip_id="c", skeleton=motion.skeleton,
                        xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=30.0,
                        units="mm", hand="right")


def test_the_command_reports_missing_blender(no_blender, tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=4, seed=1)
    db = write_database(tmp_path / "db", motion)
    result = CliRunner().invoke(app, ["export", "--db", db, "--format", "fbx", "--out",
                                      str(tmp_path / "out")])
    assert result.exit_code == 1
    assert "error: FBX export runs Blender, which was not found" in result.stderr
    assert not any((tmp_path / "out").glob("*"))


def test_a_batch_is_one_conversion_and_a_failed_clip_is_named_after_the_others(
        monkeypatch, tmp_path):
    program = tmp_path / "blender"
    program.write_text("")
    monkeypatch.setenv(BLENDER_VARIABLE, str(program))
    batches = []

    def convert(conversions):
        """Blender as the converter's report describes it: bravo fails, the rest are written."""
        batches.append([c.clip_id for c in conversions])
        for conversion in conversions:
            if conversion.clip_id != "bravo":
                conversion.target.write_bytes(conversion.source.read_bytes())
        return {"bravo": "RuntimeError: Bad glTF"}

    monkeypatch.setattr(fbx, "convert_to_fbx", convert)
    for seed, clip_id in enumerate(("alpha", "bravo", "charlie")):
        motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=4, seed=seed)
        db = write_database(tmp_path / "db", motion, clip_id=clip_id)
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["export", "--db", db, "--format", "fbx", "--out", str(out)])
    assert batches == [["alpha", "bravo", "charlie"]]
    assert result.exit_code == 1
    assert result.stdout.split() == [str(out / "alpha.fbx"), str(out / "charlie.fbx")]
    assert "clip bravo: RuntimeError: Bad glTF" in result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["alpha.fbx", "charlie.fbx"]


def test_a_blender_that_dies_mid_batch_leaves_no_clip_converted(monkeypatch, tmp_path):
    """A file Blender was writing when it died may be cut short: no clip counts as written."""
    crash = ("import json, sys; batch = json.load(open(sys.argv[2])); "
             "open(batch['conversions'][0]['target'], 'wb').write(b'Kaydara FBX'); "
             "sys.exit(139)")
    program = tmp_path / "python3.11"
    program.write_text(f"#!/bin/sh\nexec {sys.executable} -c \"{crash}\" \"$@\"\n")
    program.chmod(0o755)
    monkeypatch.setenv(BLENDER_VARIABLE, str(program))
    conversions = [fbx.FbxConversion(clip_id=name, source=tmp_path / f"{name}.glb",
                                     target=tmp_path / f"{name}.fbx", fps=30.0, n_frames=2)
                   for name in ("first", "second")]
    failed = fbx.convert_to_fbx(conversions)
    assert (tmp_path / "first.fbx").is_file()
    assert sorted(failed) == ["first", "second"]
    assert "exit status 139" in failed["first"]
