"""``handdb export``: many clips at once, in any format, run as a user runs it."""

import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from handdb.cli import app
from handdb.export import FORMATS
from handdb.export.bvh import depth_first_order
from handdb.export.placement import at_origin
from handdb.export.rotations import joint_rotations, motion_positions
from handdb.export.stored import read_stored_motion
from handdb.hand.skeletons import load_skeleton
from handdb.store.database import Store
from handdb.store.query import query
from tests.integration.cli.test_export_cli import write_database
from tests.support.axes import y_up
from tests.support.gltf_reading import open_gltf
from tests.support.motions import make_hinge_motion
from tests.support.usd_reading import joint_world_positions, open_skeleton
from tests.unit.export.test_bvh import bvh_positions, parse_bvh
from tests.unit.export.test_c3d_export import FLOAT32_MM, read_with_c3d_package
from tests.unit.export.test_gltf import FLOAT32_M
from tests.unit.export.test_trc import read_trc

runner = CliRunner()

#: Clips of the synthetic database; ``gappy`` has frames without every joint.
COMPLETE = ("alpha", "bravo")
GAPPY = "gappy"


@pytest.fixture(scope="module")
def database(tmp_path_factory):
    folder = tmp_path_factory.mktemp("many") / "db"
    skeleton = load_skeleton("mediapipe21")
    motions = {}
    for seed, clip_id in enumerate((*COMPLETE, GAPPY)):
        motion = make_hinge_motion(skeleton, n_frames=12, seed=seed)
        if clip_id == GAPPY:
            motion.xyz[4:6, skeleton.index("ring_tip")] = np.nan
        db = write_database(folder, motion, clip_id=clip_id)
        motions[clip_id] = motion.xyz
    return db, motions


def export(*args):
    return runner.invoke(app, ["export", *map(str, args)])


def test_every_clip_is_written_when_none_is_named(database, tmp_path):
    db, motions = database
    result = export("--db", db, "--format", "trc", "--out", tmp_path / "trc")
    assert result.exit_code == 0, result.output
    written = sorted(tmp_path.joinpath("trc").iterdir())
    assert [p.name for p in written] == ["alpha.trc", "bravo.trc", "gappy.trc"]
    assert result.stdout.split() == [str(p) for p in written]
    gappy = read_trc(tmp_path / "trc" / "gappy.trc")["xyz"]
    np.testing.assert_array_equal(np.isnan(gappy), np.isnan(motions[GAPPY]))


def test_a_posed_format_skips_the_clip_with_unplaced_joints(database, tmp_path):
    db, _ = database
    result = export("--db", db, "--format", "bvh", "--out", tmp_path / "bvh")
    assert result.exit_code == 3, result.output
    assert sorted(p.name for p in (tmp_path / "bvh").iterdir()) == ["alpha.bvh", "bravo.bvh"]
    assert ("skipped gappy: 2 of 12 frames have joints gap filling could not place, and bvh "
            "needs every joint posed") in result.stderr


def test_usd_keys_the_frames_that_place_every_joint(database, tmp_path):
    db, motions = database
    result = export("--db", db, "--format", "usd", "--out", tmp_path / "usd", GAPPY)
    assert result.exit_code == 0, result.output
    clip = open_skeleton(tmp_path / "usd" / f"{GAPPY}.usd")
    rotations = clip.skel_query.GetAnimQuery().GetPrim().GetAttribute("rotations")
    assert rotations.GetTimeSamples() == [f for f in range(12) if f not in (4, 5)]
    keyed = [0, 3, 6, 11]
    placed = y_up(at_origin(motions[GAPPY], load_skeleton("mediapipe21")))
    np.testing.assert_allclose(joint_world_positions(clip, 12)[keyed], placed[keyed],
                               atol=1e-3)


def test_named_clips_only_and_in_their_order(database, tmp_path):
    db, motions = database
    result = export("--db", db, "--format", "c3d", "--out", tmp_path, "bravo", "gappy")
    assert result.exit_code == 0, result.output
    assert result.stdout.split() == [str(tmp_path / "bravo.c3d"), str(tmp_path / "gappy.c3d")]
    xyz = read_with_c3d_package(tmp_path / "bravo.c3d")["xyz"]
    expected = y_up(motions["bravo"])
    np.testing.assert_allclose(xyz, expected, rtol=0, atol=FLOAT32_MM)


def test_an_unknown_clip_writes_nothing(database, tmp_path):
    db, _ = database
    result = export("--db", db, "--format", "trc", "--out", tmp_path / "out", "alpha", "nope")
    assert result.exit_code == 1
    assert "has no clip 'nope'" in result.stderr
    assert not (tmp_path / "out").exists()


def test_an_output_folder_that_is_a_file_is_refused(database, tmp_path):
    db, _ = database
    (tmp_path / "out").write_text("")
    result = export("--db", db, "--format", "trc", "--out", tmp_path / "out")
    assert result.exit_code == 1
    assert "out is a file, not a folder" in result.stderr


def test_a_clip_without_its_motion_is_skipped(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=5, seed=2)
    for clip_id in ("kept", "lost"):
        db = write_database(tmp_path / "db", motion, clip_id=clip_id)
    Store(db).delete("joints_3d", "lost")
    result = export("--db", db, "--format", "c3d", "--out", tmp_path / "out")
    assert result.exit_code == 3
    assert result.stdout.split() == [str(tmp_path / "out" / "kept.c3d")]
    assert "skipped lost: database" in result.stderr
    assert "has no 'joints_3d' rows for clip 'lost'" in result.stderr


def test_an_unknown_format_lists_the_choices(database, tmp_path):
    db, _ = database
    result = export("--db", db, "--format", "obj", "--out", tmp_path / "out")
    assert result.exit_code == 2
    message = " ".join(result.stderr.replace("│", " ").split())
    assert f"unknown export format 'obj'; known: {', '.join(FORMATS.names())}" in message
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def dhg_database(dhg_mm, dhg_bone_lengths, tmp_path_factory):
    """The real DHG capture stored as a clip, its bones their median measured lengths."""
    motion = SimpleNamespace(skeleton=load_skeleton("dhg22"), xyz=dhg_mm,
                             bone_lengths=dhg_bone_lengths)
    return write_database(tmp_path_factory.mktemp("dhg") / "db", motion, clip_id="dhg")


@pytest.mark.parametrize("name", ["trc", "c3d", "bvh", "usd", "glb"])
def test_real_capture_exports_in_every_format(dhg_database, dhg_mm, tmp_path, name):
    started = time.perf_counter()
    result = export("--db", dhg_database, "--format", name, "--out", tmp_path)
    seconds = time.perf_counter() - started
    assert result.exit_code == 0, result.output
    path = tmp_path / f"dhg{FORMATS[name].suffix}"
    assert result.stdout.split() == [str(path)]
    assert seconds < 10.0
    expected = y_up(dhg_mm)
    # The animation formats put the wrist of frame 0 at the origin and the hand on the floor.
    placed = y_up(at_origin(dhg_mm, load_skeleton("dhg22")))
    root = load_skeleton("dhg22").root
    np.testing.assert_allclose(placed[0, root, [0, 2]], 0.0, atol=1e-9)
    assert placed[..., 1].min() == pytest.approx(0.0, abs=1e-9)
    if name == "trc":
        trc = read_trc(path)
        assert (trc["fields"]["NumFrames"], trc["fields"]["DataRate"]) == ("95", "60")
        np.testing.assert_allclose(trc["xyz"], expected, atol=1e-6)
    elif name == "c3d":
        np.testing.assert_allclose(read_with_c3d_package(path)["xyz"], expected, rtol=0,
                                   atol=FLOAT32_MM)
    elif name == "bvh":
        skeleton = load_skeleton("dhg22")
        joints, _, values = parse_bvh(path.read_text())
        assert len(values) == 95
        assert [j["name"] for j in joints if j["name"]] == [
            skeleton.joints[j] for j in depth_first_order(skeleton)]
        # Metres, rigid bones: the joints the bones reach keeping their stored lengths.
        positions = bvh_positions(joints, values)
        read = np.stack([positions[name] for name in skeleton.joints], axis=1)
        lengths = read_stored_motion(dhg_database, "dhg").bone_lengths
        rigid = motion_positions(joint_rotations(at_origin(dhg_mm, skeleton), skeleton,
                                                 lengths, keep_lengths=True), skeleton)
        np.testing.assert_allclose(read, 1e-3 * y_up(rigid), atol=1e-6)
        np.testing.assert_allclose(read[:, skeleton.root], 1e-3 * placed[:, skeleton.root],
                                   atol=1e-6)
    elif name == "glb":
        np.testing.assert_allclose(open_gltf(path).joint_world_positions(), 1e-3 * placed,
                                   atol=FLOAT32_M)
    else:
        np.testing.assert_allclose(joint_world_positions(open_skeleton(path), 95), placed,
                                   atol=1e-3)


@pytest.mark.parametrize(("flag", "name"), [("--camera-frame", "glb"), ("--at-origin", "trc")])
def test_the_placement_flag_overrides_the_formats_default(database, tmp_path, flag, name):
    db, motions = database
    result = export("--db", db, "--format", name, "--out", tmp_path, flag, "alpha")
    assert result.exit_code == 0, result.output
    skeleton = load_skeleton("mediapipe21")
    path = tmp_path / f"alpha{FORMATS[name].suffix}"
    if name == "glb":
        np.testing.assert_allclose(open_gltf(path).joint_world_positions(),
                                   1e-3 * y_up(motions["alpha"]), atol=FLOAT32_M)
    else:
        xyz = read_trc(path)["xyz"]
        np.testing.assert_allclose(xyz, y_up(at_origin(motions["alpha"], skeleton)), atol=1e-6)
        np.testing.assert_allclose(xyz[0, skeleton.root, [0, 2]], 0.0, atol=1e-6)
        assert np.nanmin(xyz[..., 1]) == pytest.approx(0.0, abs=1e-6)


def test_a_built_database_exports_every_clip_from_the_command_line(demo_db, tmp_path):
    """The demo build's clips, through the installed command's entry point in a new process."""
    command = [sys.executable, "-c", "from handdb.cli import main; main()", "export", "--db",
               demo_db]
    clip_ids = query(demo_db, "SELECT clip_id FROM clips ORDER BY clip_id").column(0).to_pylist()
    assert len(clip_ids) == 2
    for name in ("trc", "glb"):
        run = subprocess.run([*command, "--format", name, "--out", str(tmp_path / name)],
                             capture_output=True, text=True, timeout=300, check=False)
        assert run.returncode == 0, run.stderr[-2000:]
        assert run.stdout.split() == [str(tmp_path / name / f"{clip_id}.{name}")
                                      for clip_id in clip_ids]
    for clip_id in clip_ids:
        rows = query(demo_db, "SELECT frame, joint_index, x, y, z FROM joints_3d WHERE clip_id = "
                     f"'{clip_id}' ORDER BY frame, joint_index").to_pydict()
        trc = read_trc(tmp_path / "trc" / f"{clip_id}.trc")
        xyz = np.full(trc["xyz"].shape, np.nan)
        xyz[rows["frame"], rows["joint_index"]] = np.column_stack([rows[a] for a in "xyz"])
        expected = y_up(xyz)
        np.testing.assert_allclose(trc["xyz"], expected, atol=1e-6)
        skeleton = load_skeleton(query(demo_db, "SELECT skeleton FROM clips WHERE clip_id = "
                                       f"'{clip_id}'").column(0)[0].as_py())
        gltf = open_gltf(tmp_path / "glb" / f"{clip_id}.glb").joint_world_positions()
        np.testing.assert_allclose(gltf, 1e-3 * y_up(at_origin(xyz, skeleton)), atol=FLOAT32_M)
