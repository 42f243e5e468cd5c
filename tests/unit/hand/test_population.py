"""Populations of hands: as varied as real hands, within what hands are."""

import numpy as np
import pytest

from handdb.hand.anatomy import BUCHHOLZ_1992, xray_phalanx_ratios
from handdb.hand.population import HAND_LENGTH_MM, THUMB_BASE_HEIGHT_RANGE, sample_shape
from handdb.hand.skeletons import FINGERS, load_skeleton

#: Tolerance on a drawn phalanx ratio beyond the X-ray range: ratios are convex mixtures of
#: the X-ray hands', so only floating-point error may cross it.
RATIO_TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def population():
    return [sample_shape(np.random.default_rng(seed)) for seed in range(60)]


def phalanx_ratios(shape, finger):
    skeleton = load_skeleton("mediapipe21")
    lengths = shape.bone_lengths(skeleton)
    joints = ("ip", "tip") if finger == "thumb" else ("pip", "dip", "tip")
    phalanges = lengths[[skeleton.index(f"{finger}_{j}") for j in joints]]
    return phalanges / phalanges.sum()


@pytest.mark.parametrize("finger", FINGERS)
def test_phalanx_ratios_lie_within_the_xray_range(population, finger):
    observed = xray_phalanx_ratios(finger)
    for shape in population:
        ratios = phalanx_ratios(shape, finger)
        assert np.all(ratios >= observed.min(axis=0) - RATIO_TOLERANCE)
        assert np.all(ratios <= observed.max(axis=0) + RATIO_TOLERANCE)


def test_hand_lengths_spread_over_the_adult_range(population):
    lengths = np.array([shape.hand_length for shape in population])
    low, high = HAND_LENGTH_MM[2]
    assert low * 0.95 <= lengths.min() and lengths.max() <= high * 1.05
    assert lengths.std() > 6.0


def test_the_thumb_base_sits_anywhere_from_the_palm_plane_to_well_in_front(population):
    heights = np.array([shape.point("thumb_cmc")[2] / shape.hand_length
                        for shape in population])
    low, high = THUMB_BASE_HEIGHT_RANGE
    assert heights.min() < low + 0.03 and heights.max() > high - 0.03


def test_wrist_points_move_as_annotations_differ(population):
    wrists = np.stack([shape.point("wrist") for shape in population])
    assert wrists.std(axis=0).min() > 1.0


def test_equal_seeds_give_equal_hands_and_different_seeds_differ():
    first = sample_shape(np.random.default_rng(7))
    again = sample_shape(np.random.default_rng(7))
    other = sample_shape(np.random.default_rng(8))
    skeleton = load_skeleton("mediapipe21")
    np.testing.assert_array_equal(first.positions(skeleton), again.positions(skeleton))
    assert not np.allclose(first.positions(skeleton), other.positions(skeleton))


def test_metacarpals_and_fingers_vary_by_a_few_percent_about_buchholz(population):
    for shape in population:
        length = shape.hand_length
        for finger in FINGERS[1:]:
            mcp = shape.point(f"{finger}_mcp")
            reach = np.linalg.norm(shape.point(f"{finger}_tip") - mcp) / length
            expected = sum(BUCHHOLZ_1992[finger][1:])
            assert abs(reach / expected - 1.0) < 0.2
