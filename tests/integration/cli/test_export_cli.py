from dataclasses import replace

import numpy as np
import pyarrow as pa
import pytest
from typer.testing import CliRunner

from handdb.cli.export import app
from handdb.export.placement import at_origin
from handdb.export.stored import read_stored_motion
from handdb.hand.skeletons import load_skeleton
from handdb.store import tables
from handdb.store.database import Store
from tests.support.axes import y_up
from tests.support.motions import make_hinge_motion
from tests.support.usd_reading import joint_world_positions, open_skeleton
from tests.unit.export.test_bvh import bvh_positions, parse_bvh

CLIP_ID = "s01_wave-2"


def table_with(name, columns):
    """Table ``name`` with ``columns``; every other column null or a neutral value."""
    n = max(len(v) for v in columns.values() if isinstance(v, list | np.ndarray))
    neutral = {pa.string(): "", pa.bool_(): False}
    filled = {}
    for field in tables.schema(name):
        if field.name in columns:
            filled[field.name] = columns[field.name]
        elif field.nullable:
            filled[field.name] = [None] * n
        elif pa.types.is_list(field.type):
            filled[field.name] = [[]] * n
        else:
            filled[field.name] = [neutral.get(field.type, 0)] * n
    return tables.from_columns(name, filled)


def write_database(folder, motion, clip_id=CLIP_ID):
    """A database holding ``motion`` as clip ``clip_id``; return its location."""
    skeleton = motion.skeleton
    T, J = motion.xyz.shape[:2]
    store = Store(str(folder))
    store.write("clips", clip_id, table_with("clips", {
        "clip_id": [clip_id], "skeleton": [skeleton.name], "hand": ["left"], "fps": [60.0],
        "units": ["mm"], "n_frames": [T], "n_joints": [J]}))
    frame, joint = np.meshgrid(np.arange(T), np.arange(J), indexing="ij")
    store.write("joints_3d", clip_id, table_with("joints_3d", {
        "clip_id": [clip_id] * (T * J), "frame": frame.ravel(), "joint_index": joint.ravel(),
        "joint": [skeleton.joints[j] for j in joint.ravel()],
        "x": motion.xyz[..., 0].ravel(), "y": motion.xyz[..., 1].ravel(),
        "z": motion.xyz[..., 2].ravel()}))
    bones = list(skeleton.bone_names)
    store.write("bone_lengths", clip_id, table_with("bone_lengths", {
        "clip_id": [clip_id] * len(bones), "bone": bones,
        "length": [motion.bone_lengths[skeleton.index(b)] for b in bones]}))
    return store.url


@pytest.fixture
def database(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=24, seed=7)
    return write_database(tmp_path / "db", motion), motion


def test_read_stored_motion(database):
    db, motion = database
    stored = read_stored_motion(db, CLIP_ID)
    assert (stored.hand, stored.units, stored.fps) == ("left", "mm", 60.0)
    np.testing.assert_array_equal(stored.xyz, motion.xyz)
    root = load_skeleton("mediapipe21").root
    assert np.isnan(stored.bone_lengths[root])
    np.testing.assert_array_equal(np.delete(stored.bone_lengths, root),
                                  np.delete(motion.bone_lengths, root))


@pytest.mark.parametrize("suffix", [".usda", ".usdc", ".usdz"])
def test_export_usd_command(database, tmp_path, suffix):
    db, motion = database
    out = tmp_path / "out" / f"{CLIP_ID}{suffix}"
    result = CliRunner().invoke(app, ["export-usd", "--clip", CLIP_ID, "--out", str(out),
                                      "--db", db])
    assert result.exit_code == 0, result.output
    clip = open_skeleton(out)
    assert clip.stage.GetTimeCodesPerSecond() == 60.0
    stage_xyz = joint_world_positions(clip, len(motion.xyz))
    np.testing.assert_allclose(stage_xyz, y_up(at_origin(motion.xyz, motion.skeleton)),
                               atol=1e-3)
    # On the floor, the wrist of frame 0 above the origin.
    np.testing.assert_allclose(stage_xyz[0, motion.skeleton.root, [0, 2]], 0.0, atol=1e-3)
    assert stage_xyz[..., 1].min() == pytest.approx(0.0, abs=1e-3)


def test_export_usd_in_camera_coordinates(database, tmp_path):
    db, motion = database
    out = tmp_path / "clip.usda"
    result = CliRunner().invoke(app, ["export-usd", "--clip", CLIP_ID, "--out", str(out),
                                      "--db", db, "--camera-frame"])
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(joint_world_positions(open_skeleton(out), len(motion.xyz)),
                               y_up(motion.xyz), atol=1e-3)


def test_export_bvh_command(database, tmp_path):
    db, motion = database
    out = tmp_path / "clip.bvh"
    result = CliRunner().invoke(app, ["export-bvh", "--clip", CLIP_ID, "--out", str(out),
                                      "--db", db])
    assert result.exit_code == 0, result.output
    joints, _, values = parse_bvh(out.read_text())
    tip = at_origin(motion.xyz, motion.skeleton)[:, motion.skeleton.index("index_tip")]
    np.testing.assert_allclose(bvh_positions(joints, values)["index_tip"],
                               1e-3 * y_up(tip), atol=1e-6)   # metres


@pytest.mark.parametrize("keep_lengths", [False, True])
def test_export_usd_of_noisy_joints(tmp_path, keep_lengths):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=10, seed=8)
    noisy = replace(motion, xyz=motion.xyz + np.random.default_rng(0).normal(
        scale=3.0, size=motion.xyz.shape))
    db = write_database(tmp_path / "db", noisy)
    out = tmp_path / "clip.usdc"
    flag = ["--keep-lengths"] if keep_lengths else []
    result = CliRunner().invoke(app, ["export-usd", "--clip", CLIP_ID, "--out", str(out),
                                      "--db", db, *flag])
    assert result.exit_code == 0, result.output
    stage_xyz = joint_world_positions(open_skeleton(out), len(noisy.xyz))
    parent, child = motion.skeleton.bones.T
    bones = np.linalg.norm(stage_xyz[:, child] - stage_xyz[:, parent], axis=-1)
    if keep_lengths:
        np.testing.assert_allclose(bones, np.broadcast_to(motion.bone_lengths[child],
                                                          bones.shape), atol=1e-3)
    else:
        np.testing.assert_allclose(stage_xyz, y_up(at_origin(noisy.xyz, motion.skeleton)),
                                   atol=1e-3)


def test_unknown_clip_and_wrong_suffix_are_reported(database, tmp_path):
    db, _ = database
    result = CliRunner().invoke(app, ["export-usd", "--clip", "nope", "--out",
                                      str(tmp_path / "x.usda"), "--db", db])
    assert result.exit_code == 1
    assert "no 'clips' rows for clip 'nope'" in result.output
    result = CliRunner().invoke(app, ["export-bvh", "--clip", CLIP_ID, "--out",
                                      str(tmp_path / "x.usda"), "--db", db])
    assert result.exit_code == 2
    assert not (tmp_path / "x.usda").exists()
