"""Synthetic motions drive the kinematic model: names, root placement, hands of the population."""

import numpy as np
import pytest

from handdb.errors import ParameterError, SkeletonError
from handdb.hand.model import forward_kinematics
from handdb.hand.skeletons import load_skeleton
from handdb.synthetic.hands import make_hand, thesis_hand
from handdb.synthetic.kinematics import (
    ANGLE_INDEX,
    ANGLE_LIMITS,
    ANGLE_NAMES,
    N_ANGLES,
    PALM_TO_CAMERA,
    clip_to_limits,
    local_positions,
    model_poses,
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


def test_every_joint_angle_of_the_model_has_a_name():
    model = make_hand()
    assert sorted(name.replace(".", "_") for name in model.dof_names[6:]) == sorted(ANGLE_NAMES)
    assert N_ANGLES == 27


@pytest.mark.parametrize("name", MODELS)
def test_every_frame_keeps_the_models_bone_lengths(name, random_angles, random_rotations):
    model = MODELS[name]()
    translation = np.random.default_rng(0).normal(0.0, 100.0, (len(random_angles), 3))
    xyz = forward_kinematics(model, model_poses(model, random_angles, random_rotations,
                                                translation))
    np.testing.assert_allclose(bone_lengths_of(xyz, model),
                               np.broadcast_to(model.bone_lengths, (len(xyz),
                                                                    len(model.bone_lengths))),
                               rtol=0, atol=1e-9)


def test_root_rotation_and_translation_act_on_the_local_pose(random_angles, random_rotations):
    model = make_hand(seed=4)
    translation = np.arange(len(random_angles) * 3, dtype=float).reshape(-1, 3)
    local = local_positions(model, random_angles)
    xyz = forward_kinematics(model, model_poses(model, random_angles, random_rotations,
                                                translation))
    for t in (0, 17, 49):
        np.testing.assert_allclose(xyz[t], local[t] @ random_rotations[t].T + translation[t],
                                   atol=1e-9)


def test_default_root_shows_the_palm_fingers_up():
    model = make_hand()
    xyz = forward_kinematics(model, model_poses(model, np.zeros((1, N_ANGLES))))[0]
    skeleton = model.skeleton
    assert xyz[skeleton.index("middle_tip"), 1] < xyz[skeleton.index("wrist"), 1]
    assert xyz[skeleton.index("thumb_tip"), 0] > xyz[skeleton.index("little_tip"), 0]
    rest = local_positions(model, np.zeros((1, N_ANGLES)))[0]
    np.testing.assert_allclose(xyz, rest @ PALM_TO_CAMERA.T, atol=1e-12)


@pytest.mark.parametrize("finger", ["index", "middle", "ring", "little"])
def test_flexion_turns_the_fingertip_towards_a_camera_the_palm_faces(finger):
    model = make_hand(seed=9)
    angles = np.zeros((2, N_ANGLES))
    angles[1, ANGLE_INDEX[f"{finger}_pip_flexion"]] = np.radians(60.0)
    camera = forward_kinematics(model, model_poses(model, angles))
    tip = model.skeleton.index(f"{finger}_tip")
    assert camera[1, tip, 2] < camera[0, tip, 2] - 1.0


def test_left_hand_is_the_mirror_image(random_angles):
    right = local_positions(make_hand(seed=3), random_angles)
    left = local_positions(make_hand(seed=3, hand="left"), random_angles)
    np.testing.assert_allclose(left, right * [-1.0, 1.0, 1.0], atol=1e-12)


def test_clip_to_limits_bounds_every_angle():
    wild = np.linspace(-10.0, 10.0, 7)[:, None] * np.ones(N_ANGLES)
    clipped = clip_to_limits(wild)
    assert np.all(clipped >= ANGLE_LIMITS[:, 0]) and np.all(clipped <= ANGLE_LIMITS[:, 1])
    assert np.all(ANGLE_LIMITS[:, 0] < ANGLE_LIMITS[:, 1])


def test_angles_of_the_wrong_shape_are_refused():
    with pytest.raises(ValueError, match=r"shape \(T, 27\)"):
        local_positions(make_hand(), np.zeros((4, 3)))


def test_seeds_draw_different_hands_and_no_seed_the_average_one():
    assert not np.allclose(make_hand(seed=7).bone_lengths, make_hand(seed=8).bone_lengths)
    np.testing.assert_array_equal(make_hand(seed=7).bone_lengths, make_hand(seed=7).bone_lengths)
    np.testing.assert_array_equal(make_hand().bone_lengths, make_hand().bone_lengths)


def test_thesis_hand_uses_the_appendix_lengths_exactly_and_hangs_from_the_palm_fold():
    model = thesis_hand()
    skeleton = load_skeleton("thesis21")
    assert model.units == "cm"
    lengths = dict(zip(skeleton.bone_names, model.bone_lengths, strict=True))
    assert lengths == skeleton.reference_lengths
    rest = forward_kinematics(model, model.rest_pose())
    np.testing.assert_allclose(rest[:, 2], 0.0, atol=1e-12)  # the Maya hand is flat


@pytest.mark.parametrize(("kwargs", "error", "message"), [
    ({"hand": "both"}, ParameterError, "hand must be one of left, right, got 'both'"),
    ({"hand_length_mm": 0.0}, ParameterError, "hand_length_mm"),
    ({"skeleton": "nope"}, SkeletonError, "unknown skeleton"),
])
def test_bad_arguments_are_refused(kwargs, error, message):
    with pytest.raises(error, match=message):
        make_hand(**kwargs)
