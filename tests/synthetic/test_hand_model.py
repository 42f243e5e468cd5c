"""The procedural hand: proportions, rest pose, presets, per-subject variation."""

import numpy as np
import pytest

from handdb.hand.skeletons import FINGERS, load_skeleton
from handdb.synthetic.hand_model import make_hand, thesis_hand, xray_ratios

PRESETS = ("mediapipe21", "dhg22", "thesis21")

#: Tolerance on a generated phalanx ratio beyond the X-ray range: ratios are drawn inside
#: the observed range, so only floating-point error may cross it.
RATIO_TOLERANCE = 1e-9


def phalanx_ratios(model, finger):
    """Relative lengths of the phalanges of ``finger`` (bones beyond its MCP)."""
    skeleton = model.skeleton
    chain = skeleton.finger_chain(finger)
    mcp = skeleton.index(f"{finger}_mcp")
    phalanges = model.bone_lengths[chain[chain > mcp]]
    return phalanges / phalanges.sum()


@pytest.mark.parametrize("seed", [None, *range(20)])
@pytest.mark.parametrize("finger", FINGERS)
def test_phalanx_ratios_lie_within_the_xray_range(seed, finger):
    ratios = phalanx_ratios(make_hand(seed=seed), finger)
    observed = xray_ratios(finger)
    assert np.all(ratios >= observed.min(axis=0) - RATIO_TOLERANCE)
    assert np.all(ratios <= observed.max(axis=0) + RATIO_TOLERANCE)


def test_mean_hand_has_the_mean_xray_ratios_of_the_index():
    # Chaudhry et al. Table 1, index finger, images 1a-1e: J1, J2, J3.
    phalanges = np.array([[339.96, 188.83, 169.67], [342.47, 195.24, 186.70],
                          [359.67, 206.58, 173.53], [417.16, 225.70, 183.67],
                          [375.25, 214.96, 203.47]])
    per_image = phalanges / phalanges.sum(axis=1, keepdims=True)
    np.testing.assert_allclose(phalanx_ratios(make_hand(), "index"), per_image.mean(axis=0),
                               rtol=1e-12)


@pytest.mark.parametrize("preset", PRESETS)
def test_every_bone_has_a_positive_length_and_the_root_none(preset):
    model = make_hand(preset)
    skeleton = load_skeleton(preset)
    assert np.isnan(model.bone_lengths[skeleton.root])
    children = skeleton.bones[:, 1]
    assert np.all(model.bone_lengths[children] > 0)
    assert set(model.bone_length_dict()) == set(skeleton.bone_names)


@pytest.mark.parametrize("length", [160.0, 185.0, 210.0])
def test_hand_length_is_the_requested_one(length):
    model = make_hand(hand_length_mm=length)
    assert model.hand_length == pytest.approx(length, rel=0.01)


def test_rest_pose_is_flat_with_the_thumb_radial_and_the_fingers_distal():
    right, left = make_hand(hand="right"), make_hand(hand="left")
    skeleton = right.skeleton
    pose = right.rest_pose
    np.testing.assert_allclose(pose[:, 2], 0.0, atol=1e-12)
    assert pose[skeleton.index("thumb_tip"), 0] > 0
    assert pose[skeleton.index("little_tip"), 0] < 0
    middle = pose[skeleton.finger_chain("middle")]
    np.testing.assert_allclose(middle[:, 0], 0.0, atol=1e-9)
    assert np.all(np.diff(middle[:, 1]) > 0)
    np.testing.assert_allclose(left.rest_pose, pose * [-1.0, 1.0, 1.0])


def test_bone_frames_are_rotations_along_their_bones():
    model = make_hand("dhg22", seed=3)
    frames = model.bone_frames
    np.testing.assert_allclose(frames @ frames.transpose(0, 2, 1),
                               np.broadcast_to(np.eye(3), frames.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(frames), 1.0)
    parents, children = model.skeleton.bones.T
    offsets = model.rest_pose[children] - model.rest_pose[parents]
    np.testing.assert_allclose(offsets, model.bone_lengths[children, None]
                               * frames[children, :, 1], atol=1e-12)


def test_seeds_vary_lengths_by_a_few_percent():
    mean = make_hand()
    subjects = np.stack([make_hand(seed=s).bone_lengths for s in range(40)])
    relative = subjects / mean.bone_lengths - 1.0
    finite = relative[:, ~np.isnan(mean.bone_lengths)]
    assert 0.01 < finite.std() < 0.06
    assert np.abs(finite).max() < 0.15
    np.testing.assert_array_equal(make_hand(seed=7).bone_lengths, make_hand(seed=7).bone_lengths)
    assert not np.allclose(make_hand(seed=7).bone_lengths, make_hand(seed=8).bone_lengths)


def test_thesis_hand_uses_the_appendix_lengths_exactly():
    model = thesis_hand()
    skeleton = load_skeleton("thesis21")
    assert model.units == "cm"
    assert model.bone_length_dict() == skeleton.reference_lengths
    assert model.bone_length_dict()["index_mcp"] == 2.81398


def test_thesis21_procedural_hand_hangs_from_the_palm_fold():
    model = make_hand("thesis21")
    pose = model.rest_pose
    skeleton = model.skeleton
    fold, wrist = pose[skeleton.index("palm_fold")], pose[skeleton.index("wrist")]
    middle_mcp = pose[skeleton.index("middle_mcp")]
    assert wrist[1] < fold[1] < middle_mcp[1]


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"hand": "both"}, "hand must be"),
    ({"hand_length_mm": 0.0}, "hand_length_mm"),
    ({"skeleton": "nope"}, "unknown skeleton"),
])
def test_bad_arguments_are_refused(kwargs, message):
    with pytest.raises(Exception, match=message):
        make_hand(**kwargs)
