"""A hand at rest: the average hand's proportions, and shapes with other bone lengths."""

import numpy as np
import pytest

from handdb.errors import SkeletonError
from handdb.hand.anatomy import BUCHHOLZ_1992, xray_phalanx_ratios
from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import FINGERS, load_skeleton

PRESETS = ("mediapipe21", "dhg22", "thesis21")


@pytest.mark.parametrize("length", [160.0, 185.0, 210.0])
def test_the_mean_hand_has_the_length_asked_for(length):
    assert mean_shape(length).hand_length == pytest.approx(length, rel=0.01)


def test_the_mean_hand_has_buchholz_lengths_split_in_the_xray_shares():
    shape = mean_shape(200.0)
    skeleton = load_skeleton("mediapipe21")
    lengths = shape.bone_lengths(skeleton)
    for finger in FINGERS:
        ends = ("mcp", "ip", "tip") if finger == "thumb" else ("mcp", "pip", "dip", "tip")
        chain = [skeleton.index(f"{finger}_{j}") for j in ends]
        metacarpal, *phalanges = BUCHHOLZ_1992[finger]
        if finger == "thumb":
            assert lengths[chain[0]] / 200.0 == pytest.approx(metacarpal)
        assert lengths[chain[1:]].sum() / 200.0 == pytest.approx(sum(phalanges))
        shares = lengths[chain[1:]] / lengths[chain[1:]].sum()
        np.testing.assert_allclose(shares, xray_phalanx_ratios(finger).mean(axis=0),
                                   atol=1e-9)


def test_the_mean_hand_faces_the_frame_thumb_radial_thumb_base_palmar():
    shape = mean_shape()
    assert shape.point("thumb_tip")[0] > 0 > shape.point("little_tip")[0]
    middle = np.stack([shape.point(f"middle_{j}") for j in ("mcp", "pip", "dip", "tip")])
    np.testing.assert_allclose(middle[:, 0], 0.0, atol=1e-9)
    assert np.all(np.diff(middle[:, 1]) > 0)
    assert shape.point("thumb_cmc")[2] > 5.0
    assert shape.point("wrist")[1] < shape.point("palm_fold")[1] < shape.point("middle_mcp")[1]


@pytest.mark.parametrize("preset", PRESETS)
def test_new_bone_lengths_keep_every_direction(preset):
    skeleton = load_skeleton(preset)
    shape = mean_shape()
    lengths = shape.bone_lengths(skeleton) * np.linspace(0.8, 1.2, skeleton.n_joints)
    lengths[skeleton.index("index_dip")] = np.nan
    changed = shape.with_bone_lengths(skeleton, lengths)
    after = changed.bone_lengths(skeleton)
    known = np.isfinite(lengths)
    np.testing.assert_allclose(after[known], lengths[known])
    np.testing.assert_allclose(after[skeleton.index("index_dip")],
                               shape.bone_lengths(skeleton)[skeleton.index("index_dip")])
    parent, child = skeleton.bones.T
    before_dirs = shape.positions(skeleton)[child] - shape.positions(skeleton)[parent]
    after_dirs = changed.positions(skeleton)[child] - changed.positions(skeleton)[parent]
    cosine = np.sum(before_dirs * after_dirs, axis=1) / (
        np.linalg.norm(before_dirs, axis=1) * np.linalg.norm(after_dirs, axis=1))
    np.testing.assert_allclose(cosine, 1.0)


def test_the_thumb_flexes_across_the_palm():
    side = mean_shape().flexion_side("thumb")
    assert side[2] > 0.3 and side[0] < -0.5
    np.testing.assert_allclose(mean_shape().flexion_side("index"), [0.0, 0.0, 1.0])


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="hand_length_mm"):
        mean_shape(0.0)
    with pytest.raises(SkeletonError, match="no joint 'elbow'"):
        mean_shape().point("elbow")
    with pytest.raises(SkeletonError, match="lengths must be"):
        mean_shape().with_bone_lengths(load_skeleton("mediapipe21"), np.ones(3))
