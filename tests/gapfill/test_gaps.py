import numpy as np

from handdb.gapfill.gaps import find_gaps


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
