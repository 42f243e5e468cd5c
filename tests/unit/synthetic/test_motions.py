"""Motions: joint limits, determinism, the clench, rapid gestures, speeds."""

import numpy as np
import pytest

from handdb.synthetic.hands import make_hand
from handdb.synthetic.kinematics import (
    ANGLE_INDEX,
    ANGLE_LIMITS,
    ANGLE_NAMES,
    PALM_TO_CAMERA,
    local_positions,
)
from handdb.synthetic.motions import FIST, MOTIONS, OPEN, PINCH, make_motion

#: Fastest voluntary finger-joint rotation seen in people, deg/s (fast tapping and
#: flicking reach roughly 1000-2000 deg/s).
HUMAN_PEAK_DEG_S = 2500.0


def angular_speed_deg_s(angles, fps):
    return np.degrees(np.abs(np.diff(angles, axis=0))) * fps


def rotation_angle_deg(first, second):
    """Angle of the rotation taking ``first`` to ``second`` (both ``(..., 3, 3)``), deg."""
    relative = np.swapaxes(first, -1, -2) @ second
    cosine = (np.trace(relative, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def wrist_angle_deg(rotation):
    """Angle of each frame's rotation away from the palm-to-camera pose, degrees."""
    return rotation_angle_deg(PALM_TO_CAMERA, rotation)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("name", MOTIONS)
def test_motions_stay_within_the_joint_limits_and_are_finite(name, seed):
    motion = make_motion(name, 240, seed=seed)
    assert motion.angles.shape == (240, len(ANGLE_LIMITS))
    assert np.isfinite(motion.angles).all() and np.isfinite(motion.root_offset).all()
    assert np.all(motion.angles >= ANGLE_LIMITS[:, 0] - 1e-12)
    assert np.all(motion.angles <= ANGLE_LIMITS[:, 1] + 1e-12)
    rotation = motion.root_rotation
    np.testing.assert_allclose(rotation @ rotation.transpose(0, 2, 1),
                               np.broadcast_to(np.eye(3), rotation.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(rotation), 1.0)


@pytest.mark.parametrize("name", MOTIONS)
def test_equal_seeds_give_equal_motions_and_different_seeds_differ(name):
    first, again, other = (make_motion(name, 120, seed=s) for s in (3, 3, 4))
    np.testing.assert_array_equal(first.angles, again.angles)
    np.testing.assert_array_equal(first.root_rotation, again.root_rotation)
    assert not np.allclose(first.angles, other.angles)


@pytest.mark.parametrize("name", MOTIONS)
def test_speeds_are_humanly_possible(name):
    motion = make_motion(name, 300, fps=60.0, seed=1)
    assert angular_speed_deg_s(motion.angles, 60.0).max() < HUMAN_PEAK_DEG_S
    wrist_speed = rotation_angle_deg(motion.root_rotation[:-1], motion.root_rotation[1:]) * 60.0
    assert wrist_speed.max() < HUMAN_PEAK_DEG_S


def test_clench_goes_from_open_to_a_fist_with_the_palm_still():
    motion = make_motion("clench", 100)
    np.testing.assert_allclose(motion.angles[0], OPEN, atol=1e-9)
    np.testing.assert_allclose(motion.angles[-1], FIST, atol=1e-9)
    np.testing.assert_array_equal(motion.root_rotation,
                                  np.broadcast_to(PALM_TO_CAMERA, (100, 3, 3)))
    np.testing.assert_array_equal(motion.root_offset, 0.0)
    pip = motion.angles[:, ANGLE_INDEX["middle_pip_flexion"]]
    assert np.all(np.diff(pip) >= -1e-12)


def test_clench_keeps_dip_at_two_thirds_of_pip():
    motion = make_motion("clench", 100)
    for finger in ("index", "middle", "ring", "little"):
        pip = motion.angles[:, ANGLE_INDEX[f"{finger}_pip_flexion"]]
        dip = motion.angles[:, ANGLE_INDEX[f"{finger}_dip_flexion"]]
        np.testing.assert_allclose(dip, 2.0 / 3.0 * pip, atol=1e-12)


def test_rapid_gestures_are_fast_and_turn_the_wrist_up_to_about_40_degrees():
    rapid = make_motion("rapid", 300, seed=2)
    clench = make_motion("clench", 300, seed=2)
    assert angular_speed_deg_s(rapid.angles, 30.0).max() > 400.0
    assert (angular_speed_deg_s(rapid.angles, 30.0).max()
            > 5 * angular_speed_deg_s(clench.angles, 30.0).max())
    turn = wrist_angle_deg(rapid.root_rotation)
    assert 20.0 < turn.max() < 55.0


def test_pinch_brings_the_thumb_and_index_tips_together():
    gaps = []
    for seed in (None, *range(8)):
        model = make_hand(seed=seed)
        thumb, index = model.skeleton.indices(["thumb_tip", "index_tip"])
        open_hand, pinch = local_positions(model, np.stack([OPEN, PINCH]))
        gaps.append(np.linalg.norm(pinch[thumb] - pinch[index]))
        assert np.linalg.norm(open_hand[thumb] - open_hand[index]) > 60.0
    # Joint centres of two touching finger pads are one to two pad thicknesses apart; one
    # pose pinches the average hand, and hands of the population come close.
    assert gaps[0] < 15.0 and np.median(gaps) < 25.0


def test_wave_swings_the_open_hand():
    motion = make_motion("wave", 150, seed=0)
    turn = wrist_angle_deg(motion.root_rotation)
    assert turn.max() > 15.0
    curl = motion.angles[:, ANGLE_INDEX["index_pip_flexion"]]
    assert np.degrees(curl.max()) < 30.0


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("name", MOTIONS)
def test_neighbouring_fingers_never_cross(name, seed):
    model = make_hand(seed=seed)
    local = local_positions(model, make_motion(name, 300, seed=seed).angles)
    mcp = model.skeleton.indices([f"{f}_mcp" for f in ("index", "middle", "ring", "little")])
    pip = model.skeleton.indices([f"{f}_pip" for f in ("index", "middle", "ring", "little")])
    phalanx = local[:, pip] - local[:, mcp]
    # Azimuth in the palm plane, from the distal axis toward the thumb side.
    azimuth = np.degrees(np.arctan2(phalanx[..., 0], phalanx[..., 1]))
    assert np.all(np.diff(azimuth, axis=1) < 0.0)


def test_random_motion_explores_the_range():
    motion = make_motion("random", 900, seed=0)
    span = motion.angles.max(axis=0) - motion.angles.min(axis=0)
    limits = np.diff(ANGLE_LIMITS, axis=1)[:, 0]
    flexions = [i for i, name in enumerate(ANGLE_NAMES) if name.endswith("flexion")]
    assert np.all(span[flexions] > 0.3 * limits[flexions])
    for finger in ("index", "ring", "little"):
        abduction = ANGLE_INDEX[f"{finger}_mcp_abduction"]
        assert motion.angles[:, abduction].max() > 0.5 * ANGLE_LIMITS[abduction, 1]


@pytest.mark.parametrize(("args", "message"), [
    (("dance", 10), "unknown motion"),
    (("clench", 1), "at least 2"),
])
def test_bad_arguments_are_refused(args, message):
    with pytest.raises(ValueError, match=message):
        make_motion(*args)
