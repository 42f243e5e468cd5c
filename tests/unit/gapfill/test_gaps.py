import numpy as np
import pytest

from handdb.gapfill.gaps import find_gaps, mask_points


def test_find_gaps_classifies_runs():
    missing = np.zeros((10, 3), dtype=bool)
    missing[0:2, 0] = True      # leading
    missing[4:6, 0] = True      # interior
    missing[8:, 1] = True       # trailing
    missing[:, 2] = True        # whole clip
    gaps = find_gaps(missing)
    assert gaps.joint.tolist() == [0, 0, 1, 2]
    assert gaps.start.tolist() == [0, 4, 8, 0]
    assert gaps.stop.tolist() == [2, 6, 10, 10]
    assert gaps.leading.tolist() == [True, False, False, True]
    assert gaps.trailing.tolist() == [False, False, True, True]
    assert gaps.whole_clip.tolist() == [False, False, False, True]
    assert gaps.interior.tolist() == [False, True, False, False]


def test_frames_lists_every_missing_point_once():
    rng = np.random.default_rng(1)
    missing = rng.random((50, 4)) < 0.3
    _, frame, joint = find_gaps(missing).frames()
    rebuilt = np.zeros_like(missing)
    rebuilt[frame, joint] = True
    assert np.array_equal(rebuilt, missing)
    assert frame.size == missing.sum()


@pytest.mark.parametrize("shape", [(1, 1), (2, 3), (7, 21), (400, 22)])
def test_gaps_are_the_maximal_runs_of_a_random_mask(shape):
    missing = np.random.default_rng(shape[0]).random(shape) < 0.4
    gaps = find_gaps(missing)
    _, frame, joint = gaps.frames()
    rebuilt = np.zeros_like(missing)
    rebuilt[frame, joint] = True
    assert np.array_equal(rebuilt, missing) and frame.size == missing.sum()
    padded = np.pad(missing, ((1, 1), (0, 0)))
    assert not padded[gaps.start, gaps.joint].any()        # the frame before each gap
    assert not padded[gaps.stop + 1, gaps.joint].any()     # the frame after each gap


@pytest.mark.parametrize("shape", [(0, 3), (1, 1), (5, 21), (400, 22)])
def test_mask_points_are_nonzero_in_row_major_order(shape):
    mask = np.random.default_rng(len(shape) + shape[0]).random(shape) < 0.3
    frame, joint = mask_points(mask)
    expected = np.nonzero(mask)
    assert np.array_equal(frame, expected[0]) and np.array_equal(joint, expected[1])
