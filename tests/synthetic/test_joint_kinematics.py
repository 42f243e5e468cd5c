"""Forward kinematics of the procedural hand: rigid bones, flexion sense, root transform."""

import numpy as np
import pytest

from handdb.synthetic.hand_model import make_hand, thesis_hand
from handdb.synthetic.kinematics import (
    ANGLE_INDEX,
    ANGLE_LIMITS,
    N_ANGLES,
    PALM_TO_CAMERA,
    clip_to_limits,
    forward_kinematics,
    local_kinematics,
)

MODELS = {
    "mediapipe21": lambda: make_hand("mediapipe21", seed=1),
    "dhg22": lambda: make_hand("dhg22", seed=2, hand="left"),
    "thesis21": lambda: make_hand("thesis21", seed=3),
    "thesis_reference": thesis_hand,
}


def bone_lengths_of(xyz, model):
    parents, children = model.skeleton.bones.T
    return np.linalg.norm(xyz[:, children] - xyz[:, parents], axis=-1)


@pytest.mark.parametrize("name", MODELS)
def test_every_frame_keeps_the_models_bone_lengths(name, random_angles, random_rotations):
    model = MODELS[name]()
    translation = np.random.default_rng(0).normal(0.0, 100.0, (len(random_angles), 3))
    xyz = forward_kinematics(model, random_angles, random_rotations, translation)
    expected = model.bone_lengths[model.skeleton.bones[:, 1]]
    np.testing.assert_allclose(bone_lengths_of(xyz, model),
                               np.broadcast_to(expected, (len(xyz), len(expected))),
                               rtol=0, atol=1e-9)


def test_zero_angles_give_the_rest_pose():
    model = make_hand("dhg22", seed=5)
    local = local_kinematics(model, np.zeros((3, N_ANGLES)))
    np.testing.assert_allclose(local, np.broadcast_to(model.rest_pose, local.shape), atol=1e-12)


def test_root_rotation_and_translation_act_on_the_local_pose(random_angles, random_rotations):
    model = make_hand(seed=4)
    translation = np.arange(len(random_angles) * 3, dtype=float).reshape(-1, 3)
    local = local_kinematics(model, random_angles)
    xyz = forward_kinematics(model, random_angles, random_rotations, translation)
    for t in (0, 17, 49):
        np.testing.assert_allclose(xyz[t], local[t] @ random_rotations[t].T + translation[t],
                                   atol=1e-9)


def test_default_root_shows_the_palm_fingers_up():
    model = make_hand()
    xyz = forward_kinematics(model, np.zeros((1, N_ANGLES)))[0]
    skeleton = model.skeleton
    assert xyz[skeleton.index("middle_tip"), 1] < xyz[skeleton.index("wrist"), 1]
    assert xyz[skeleton.index("thumb_tip"), 0] > xyz[skeleton.index("little_tip"), 0]
    np.testing.assert_allclose(xyz, model.rest_pose @ PALM_TO_CAMERA.T, atol=1e-12)


@pytest.mark.parametrize("finger", ["index", "middle", "ring", "little"])
@pytest.mark.parametrize("joint", ["mcp", "pip", "dip"])
def test_flexion_moves_the_fingertip_to_the_palm_side(finger, joint):
    model = make_hand(seed=9)
    angles = np.zeros((2, N_ANGLES))
    angles[1, ANGLE_INDEX[f"{finger}_{joint}_flexion"]] = np.radians(60.0)
    local = local_kinematics(model, angles)
    tip = model.skeleton.index(f"{finger}_tip")
    assert local[1, tip, 2] > local[0, tip, 2] + 1.0
    camera = forward_kinematics(model, angles)
    assert camera[1, tip, 2] < camera[0, tip, 2] - 1.0  # palm faces the camera


def test_thumb_flexion_curls_across_the_palm():
    model = make_hand()
    angles = np.zeros((2, N_ANGLES))
    for dof in ("thumb_mcp_flexion", "thumb_ip_flexion"):
        angles[1, ANGLE_INDEX[dof]] = np.radians(50.0)
    local = local_kinematics(model, angles)
    tip = model.skeleton.index("thumb_tip")
    assert local[1, tip, 2] > local[0, tip, 2]
    assert local[1, tip, 0] < local[0, tip, 0]


def test_positive_abduction_spreads_the_fingers():
    model = make_hand()
    angles = np.zeros((2, N_ANGLES))
    for finger in ("index", "ring", "little"):
        angles[1, ANGLE_INDEX[f"{finger}_mcp_abduction"]] = np.radians(10.0)
    local = local_kinematics(model, angles)
    index_tip, little_tip, ring_tip = model.skeleton.indices(["index_tip", "little_tip",
                                                              "ring_tip"])
    assert local[1, index_tip, 0] > local[0, index_tip, 0]
    assert local[1, ring_tip, 0] < local[0, ring_tip, 0]
    assert local[1, little_tip, 0] < local[0, little_tip, 0]
    np.testing.assert_allclose(local[:, :, 2], 0.0, atol=1e-12)


def test_left_hand_is_the_mirror_image(random_angles):
    right = local_kinematics(make_hand(seed=3), random_angles)
    left = local_kinematics(make_hand(seed=3, hand="left"), random_angles)
    np.testing.assert_allclose(left, right * [-1.0, 1.0, 1.0])


def test_clip_to_limits_bounds_every_angle():
    wild = np.linspace(-10.0, 10.0, 7)[:, None] * np.ones(N_ANGLES)
    clipped = clip_to_limits(wild)
    assert np.all(clipped >= ANGLE_LIMITS[:, 0]) and np.all(clipped <= ANGLE_LIMITS[:, 1])
    assert np.all(ANGLE_LIMITS[:, 0] < ANGLE_LIMITS[:, 1])


def test_angles_of_the_wrong_shape_are_refused():
    with pytest.raises(ValueError, match=r"shape \(T, 20\)"):
        local_kinematics(make_hand(), np.zeros((4, 3)))
