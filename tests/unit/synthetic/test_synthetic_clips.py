"""Synthetic clips: truth and pixels agree, stay in the image, and read back as clips."""

import json

import numpy as np
import pytest

from handdb.errors import UnknownNameError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest.sidecar import parse_sidecar
from handdb.store import tables
from handdb.synthetic import MOTIONS, synthesize_clip, thesis_clench_clip


def lengths_of(xyz, skeleton_name):
    parents, children = load_skeleton(skeleton_name).bones.T
    return np.linalg.norm(xyz[:, children] - xyz[:, parents], axis=-1)


def reproject(clip):
    """Project ``clip.xyz`` from its camera description alone."""
    width, height = clip.image_size
    if clip.camera["model"] == "orthographic":
        return clip.scale * clip.xyz[..., :2] + [width / 2.0, height / 2.0]
    cam = clip.camera
    return (np.array([cam["fx"], cam["fy"]]) * clip.xyz[..., :2] / clip.xyz[..., 2:]
            + [cam["cx"], cam["cy"]])


@pytest.mark.parametrize("camera", ["orthographic", "pinhole"])
@pytest.mark.parametrize("skeleton", ["mediapipe21", "dhg22", "thesis21"])
@pytest.mark.parametrize("motion", MOTIONS)
def test_clip_truth_is_rigid_and_its_pixels_come_from_its_camera(motion, skeleton, camera):
    clip = synthesize_clip(motion, 90, skeleton=skeleton, camera=camera, seed=11)
    n_joints = load_skeleton(skeleton).n_joints
    assert clip.xyz.shape == (90, n_joints, 3) and clip.uv.shape == (90, n_joints, 2)
    expected = [clip.bone_lengths[b] for b in load_skeleton(skeleton).bone_names]
    np.testing.assert_allclose(lengths_of(clip.xyz, skeleton),
                               np.broadcast_to(expected, (90, len(expected))), atol=1e-9)
    np.testing.assert_allclose(clip.uv, reproject(clip), atol=1e-9)


@pytest.mark.parametrize("distance_mm", [200.0, 300.0, 450.0])
@pytest.mark.parametrize("camera", ["orthographic", "pinhole"])
@pytest.mark.parametrize("motion", MOTIONS)
def test_every_joint_is_in_the_image_and_in_front_of_the_camera(motion, camera, distance_mm):
    for seed in range(4):
        clip = synthesize_clip(motion, 300, camera=camera, seed=seed, distance_mm=distance_mm)
        width, height = clip.image_size
        assert np.all(clip.uv > 0) and np.all(clip.uv[..., 0] < width)
        assert np.all(clip.uv[..., 1] < height)
        assert np.all(clip.xyz[..., 2] > 0.25 * distance_mm)
        depth_of_centre = clip.xyz[0].mean(axis=0)[2]
        assert depth_of_centre == pytest.approx(distance_mm, rel=0.2)


def test_equal_seeds_give_equal_clips_and_different_seeds_differ():
    first, again, other = (synthesize_clip("random", 60, seed=s) for s in (5, 5, 6))
    np.testing.assert_array_equal(first.xyz, again.xyz)
    np.testing.assert_array_equal(first.uv, again.uv)
    assert first.bone_lengths == again.bone_lengths
    assert not np.allclose(first.xyz, other.xyz)
    assert first.bone_lengths != other.bone_lengths


def test_left_hand_clip_mirrors_the_right_one():
    right = synthesize_clip("rapid", 60, seed=2)
    left = synthesize_clip("rapid", 60, seed=2, hand="left")
    np.testing.assert_allclose(left.xyz, right.xyz * [-1.0, 1.0, 1.0], atol=1e-9)
    np.testing.assert_allclose(left.uv[..., 0], right.image_size[0] - right.uv[..., 0],
                               atol=1e-9)


def test_pixel_noise_leaves_the_truth_exact():
    clean = synthesize_clip("wave", 200, seed=3)
    noisy = synthesize_clip("wave", 200, seed=3, noise_px=2.0)
    np.testing.assert_array_equal(noisy.xyz, clean.xyz)
    residual = noisy.uv - clean.uv
    assert residual.std() == pytest.approx(2.0, rel=0.05)


def test_sidecar_reads_back_as_a_valid_clip_spec(tmp_path):
    clip = synthesize_clip("clench", 30, camera="pinhole", seed=1)
    path = tmp_path / "synthetic_clench.clip.json"
    path.write_text(json.dumps(clip.sidecar(subject="s01")))
    spec = parse_sidecar(path)
    assert spec.skeleton == "mediapipe21" and spec.units == "mm"
    assert spec.camera.model == "pinhole" and spec.camera.fx == clip.camera["fx"]
    assert spec.bone_lengths == pytest.approx(clip.bone_lengths)
    assert (spec.image_width, spec.image_height) == clip.image_size


def test_as_clip_gives_a_fully_observed_clip_with_truth():
    synthetic = synthesize_clip("rapid", 40, camera="pinhole", seed=4, hand="left")
    clip = synthetic.as_clip("rapid_left")
    assert clip.clip_id == "rapid_left" and clip.n_frames == 40
    assert clip.spec.hand == "left" and clip.spec.camera.model == "pinhole"
    assert clip.observed.all()
    np.testing.assert_array_equal(clip.uv, synthetic.uv)
    np.testing.assert_array_equal(clip.truth, synthetic.xyz)
    assert clip.skeleton.joints == synthetic.joints


def test_truth_table_follows_the_truth_3d_contract():
    clip = synthesize_clip("clench", 12, skeleton="dhg22")
    table = clip.truth_table("c1")
    assert table.schema.equals(tables.schema("truth_3d"), check_metadata=False)
    assert table.num_rows == 12 * 22
    rows = table.to_pylist()
    row = next(r for r in rows if r["frame"] == 7 and r["joint"] == "palm")
    np.testing.assert_allclose([row["x"], row["y"], row["z"]], clip.xyz[7, 1])


def test_thesis_clench_is_the_maya_hand_closing_with_a_still_palm():
    clip = thesis_clench_clip()
    skeleton = load_skeleton("thesis21")
    assert clip.n_frames == 100 and clip.skeleton == "thesis21" and clip.units == "cm"
    assert clip.bone_lengths == skeleton.reference_lengths
    assert clip.camera == {"model": "orthographic"}
    np.testing.assert_allclose(clip.uv, 40.0 * clip.xyz[..., :2] + [960.0, 540.0])
    palm = skeleton.indices(["palm_fold", "wrist", "index_mcp", "middle_mcp", "ring_mcp",
                             "little_mcp"])
    np.testing.assert_allclose(clip.xyz[:, palm], np.broadcast_to(clip.xyz[0, palm],
                                                                  (100, len(palm), 3)))
    tips = skeleton.indices(["index_tip", "middle_tip", "ring_tip", "little_tip"])
    mcps = skeleton.indices(["index_mcp", "middle_mcp", "ring_mcp", "little_mcp"])
    start, end = clip.xyz[0], clip.xyz[-1]
    fingers = [i for i, f in enumerate(skeleton.fingers) if f != "thumb"]
    np.testing.assert_allclose(start[fingers, 2], start[0, 2], atol=1e-9)  # open: flat
    assert np.all(end[tips, 2] < end[mcps, 2])  # fist: tips in front of the palm
    assert np.all(end[tips, 1] > end[mcps, 1])  # and curled below the knuckles


def test_unknown_camera_is_refused():
    with pytest.raises(UnknownNameError, match="unknown camera model 'fisheye'"):
        synthesize_clip("clench", 10, camera="fisheye")
