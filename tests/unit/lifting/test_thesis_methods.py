import numpy as np
import pytest

from handdb.hand.skeletons import load_skeleton
from handdb.lifting import lift
from handdb.lifting.thesis import THESIS_POSITIVE_Z, inner_angle_deg, rule_chains, tip_turns
from tests.unit.lifting.conftest import ORTHOGRAPHIC


def test_inner_angle_by_law_of_cosines():
    a, b = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    assert inner_angle_deg(a, b, np.array([1.0, 1.0])) == pytest.approx(90.0)
    assert inner_angle_deg(a, b, np.array([2.0, 0.0])) == pytest.approx(180.0)
    assert inner_angle_deg(a, b, np.array([0.0, 1.0])) == pytest.approx(45.0)


def test_tip_turns_toward_palm_only_when_pip_angle_at_most_90():
    skeleton = load_skeleton("thesis21")
    chains = rule_chains(skeleton)
    y = np.zeros((3, skeleton.n_joints))
    z = np.zeros((3, skeleton.n_joints))
    a, b, c = chains[0, :3]
    y[:, a], y[:, b] = 0.0, -1.0           # A below B in the image, finger pointing up
    z[:, a], z[:, b] = 0.0, 0.0
    y[:, c] = [-2.0, -1.0, 0.0]            # straight (180°), bent 90°, bent 45°
    z[:, c] = [0.0, 1.0, 1.0]
    turned = tip_turns(y, z, chains)[:, 0]
    np.testing.assert_array_equal(turned, [False, True, True])


def test_thesis_and_nocheck_differ_exactly_at_tips(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    checked = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="thesis")
    unchecked = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="thesis-nocheck")
    differs = np.any(checked.xyz != unchecked.xyz, axis=(0, 2))
    tips = set(rule_chains(skeleton)[:, 3])
    assert {skeleton.joints[j] for j in np.flatnonzero(differs)} <= {
        skeleton.joints[j] for j in tips}
    assert differs.any()
    np.testing.assert_array_equal(checked.scale, unchecked.scale)


def test_nocheck_takes_the_thesis_direction_for_every_bone(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    result = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="thesis-nocheck")
    bones = skeleton.bones
    dz = result.xyz[:, bones[:, 1], 2] - result.xyz[:, bones[:, 0], 2]
    assert np.all(dz * THESIS_POSITIVE_Z >= 0)
    np.testing.assert_allclose(result.xyz[:, skeleton.root, 2], 0.0)
    # bone lengths are kept wherever the track allows
    length = np.linalg.norm(result.xyz[:, bones[:, 1]] - result.xyz[:, bones[:, 0]], axis=-1)
    consistent = result.length_inconsistency[:, bones[:, 1]] == 0
    np.testing.assert_allclose(length[consistent],
                               np.broadcast_to(lengths[bones[:, 1]], length.shape)[consistent])
