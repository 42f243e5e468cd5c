import numpy as np
import pytest
import trimesh

from handdb.clip import METERS_PER_UNIT
from handdb.export.mesh import (
    CAPSULE_COUNT,
    _capsules,
    hand_mesh,
    knuckle_span,
    posed_hand_mesh,
    posed_vertices,
)
from handdb.export.rotations import palm_joints, rest_positions
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.synthetic import thesis_clench_clip
from tests.support.motions import make_hinge_motion


@pytest.fixture(params=["mediapipe21", "thesis21", "dhg22"])
def motion_and_mesh(request):
    motion = make_hinge_motion(load_skeleton(request.param), n_frames=12, seed=5)
    return motion, hand_mesh(motion.skeleton, motion.bone_lengths)


def point_segment_distance(points, start, end):
    axis = end - start
    s = np.clip(np.sum((points - start) * axis, axis=-1) / np.sum(axis * axis, axis=-1), 0, 1)
    return np.linalg.norm(points - (start + s[..., None] * axis), axis=-1)


def test_skin_weights_sum_to_one_and_indices_are_joints(motion_and_mesh):
    motion, mesh = motion_and_mesh
    assert 1000 < len(mesh.faces) < 5000
    assert mesh.joint_indices.shape == mesh.joint_weights.shape == (len(mesh.vertices), 2)
    np.testing.assert_allclose(mesh.joint_weights.sum(axis=1), 1.0)
    assert mesh.joint_weights.min() >= 0
    assert mesh.joint_indices.min() >= 0
    assert mesh.joint_indices.max() < motion.skeleton.n_joints
    assert mesh.to_trimesh().is_watertight


def test_every_finger_bone_is_covered_in_the_rest_pose(motion_and_mesh):
    motion, mesh = motion_and_mesh
    skeleton = motion.skeleton
    rest = rest_positions(skeleton, motion.bone_lengths)
    covered = set(mesh.face_joints.tolist())
    for parent, child in skeleton.bones:
        if len(skeleton.children(parent)) == 1:
            assert child in covered, skeleton.joints[child]
    assert mesh.to_trimesh().contains(rest[[skeleton.root]]).all()


def test_rest_joints_pose_the_rest_mesh(motion_and_mesh):
    motion, mesh = motion_and_mesh
    rest = rest_positions(motion.skeleton, motion.bone_lengths)
    posed = posed_vertices(mesh, rest[None], motion.skeleton, motion.bone_lengths)
    np.testing.assert_allclose(posed[0], mesh.vertices, atol=1e-9)


def test_rigid_capsule_vertices_stay_on_their_posed_bone(motion_and_mesh):
    motion, mesh = motion_and_mesh
    skeleton = motion.skeleton
    rest = rest_positions(skeleton, motion.bone_lengths)
    posed = posed_vertices(mesh, motion.xyz, skeleton, motion.bone_lengths)
    rigid = (mesh.joint_weights[:, 0] == 1.0) & (mesh.joint_indices[:, 0] != skeleton.root)
    joint = mesh.joint_indices[rigid, 0]
    child = np.array([skeleton.children(j)[0] for j in joint])
    rest_distance = point_segment_distance(mesh.vertices[rigid], rest[joint], rest[child])
    posed_distance = point_segment_distance(posed[:, rigid], motion.xyz[:, joint],
                                            motion.xyz[:, child])
    np.testing.assert_allclose(posed_distance, np.broadcast_to(rest_distance, posed_distance.shape),
                               atol=1e-9)


def test_a_ray_at_a_fingertip_hits_that_finger():
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=2)
    skeleton = motion.skeleton
    rest = rest_positions(skeleton, motion.bone_lengths)
    mesh = posed_hand_mesh(rest, skeleton, motion.bone_lengths)
    tip = skeleton.index("index_tip")
    origin = rest[tip] + [0.0, -2.0, 500.0]
    _, _, faces = mesh.ray.intersects_location([origin], [[0.0, 0.0, -1.0]], multiple_hits=False)
    assert mesh.face_attributes["joint"][faces[0]] == tip


def thesis_clench_lengths():
    """The ``thesis21`` clip's own bone lengths (cm): short little-finger and thumb bones."""
    clip = thesis_clench_clip()
    skeleton = load_skeleton("thesis21")
    return skeleton, np.nan_to_num(bone_length_array(skeleton, clip.bone_lengths,
                                                     complete=True)), clip.units


@pytest.mark.parametrize("hand", ["mediapipe21", "dhg22", "thesis21", "thesis21-clench"])
def test_the_palm_and_fingers_have_a_hands_proportions(hand):
    """A slab of a palm (thick at the knuckles, broad down to the wrist) and no slivers."""
    if hand == "thesis21-clench":
        skeleton, lengths, units = thesis_clench_lengths()
    else:
        motion = make_hinge_motion(load_skeleton(hand), n_frames=2)
        skeleton, lengths, units = motion.skeleton, motion.bone_lengths, "mm"
    mesh = hand_mesh(skeleton, lengths)
    rest = rest_positions(skeleton, lengths)
    span = knuckle_span(skeleton, rest)
    wrist, mcps = palm_joints(skeleton)
    np.testing.assert_allclose(span, np.linalg.norm(rest[mcps[0]] - rest[mcps[-1]]))

    palm = mesh.vertices[np.unique(mesh.faces[mesh.face_joints == skeleton.root])]
    at_knuckles = palm[np.abs(palm[:, 1] - rest[mcps, 1].mean()) < 0.1 * span]
    at_wrist = palm[np.abs(palm[:, 1] - rest[wrist, 1]) < 0.1 * span]
    assert np.ptp(at_knuckles[:, 2]) >= 0.5 * span               # thickness at the MCPs
    assert np.ptp(at_knuckles[:, 0]) >= 1.3 * span               # breadth at the MCPs
    assert np.ptp(at_wrist[:, 0]) >= 1.0 * span                  # not a cone to the wrist

    mm = 1e3 * METERS_PER_UNIT[units]
    for parent, child in skeleton.bones:
        faces = mesh.faces[mesh.face_joints == child]
        if len(faces) == 0:
            continue
        radius = point_segment_distance(mesh.vertices[np.unique(faces)], rest[parent],
                                        rest[child]).max()
        name = skeleton.joints[child]
        assert radius >= 0.13 * span, name
        assert radius * mm >= 5.5, name                          # no hair-thin finger


def _trimesh_capsule(start, end, radius):
    length = float(np.linalg.norm(end - start))
    transform = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], (end - start) / length)
    transform[:3, 3] = (start + end) / 2
    return trimesh.creation.capsule(height=length, radius=radius, count=CAPSULE_COUNT,
                                    transform=transform)


@pytest.mark.parametrize("sizes", [[2e-4], [1e-3], [0.02], [1.0], [30.0],
                                   [30.0, 2e-4, 1.0, 1e-3]])
def test_capsules_are_trimesh_capsules_point_for_point(sizes):
    # metres to millimetres, and below a millimetre where trimesh drops faces; the last
    # batch mixes capsules computed here with capsules left to trimesh
    rng = np.random.default_rng(int(sizes[0] * 1e4) + len(sizes))
    size = np.repeat(sizes, 10 // len(sizes) + 1)[:10, None]
    starts = rng.normal(size=(10, 3)) * size
    ends = starts + rng.normal(size=(10, 3)) * size
    radii = size[:, 0] * rng.uniform(0.1, 0.6, 10)
    capsules = _capsules(starts, ends, radii)
    assert len(capsules) == 10
    for (vertices, faces), start, end, radius in zip(capsules, starts, ends, radii,
                                                     strict=True):
        expected = _trimesh_capsule(start, end, radius)
        assert np.array_equal(vertices, expected.vertices)
        assert np.array_equal(faces, expected.faces)
