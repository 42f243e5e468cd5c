import numpy as np
import pytest

from handdb.gapfill import SHORT_HISTORY, fill_gaps
from handdb.gapfill.registry import LEADING


def _still_hand(skeleton, n_frames):
    """Every joint at its own fixed place; tests then move a few coordinates."""
    rng = np.random.default_rng(0)
    place = rng.uniform(100, 300, size=(skeleton.n_joints, 2))
    return np.repeat(place[None], n_frames, axis=0)


def _table_3_1(skeleton, axis):
    uv = _still_hand(skeleton, 4)
    a, b = skeleton.index("index_dip"), skeleton.index("middle_dip")
    uv[:, a, axis] = [3, 5, 7, np.nan]
    uv[:, b, axis] = [3, 5, 4, 3]
    return uv, np.isfinite(uv).all(axis=-1), a


@pytest.mark.parametrize("axis", [0, 1])
def test_table_3_1_method_2_predicts_9_and_method_3_predicts_5(thesis21, axis):
    uv, observed, a = _table_3_1(thesis21, axis)
    assert fill_gaps(uv, observed, thesis21, "previous-diff").uv[3, a, axis] == 9
    assert fill_gaps(uv, observed, thesis21, "interfinger").uv[3, a, axis] == 5


def test_previous_holds_the_last_value_through_a_gap(thesis21):
    uv = _still_hand(thesis21, 8)
    j = thesis21.index("index_tip")
    uv[:, j, 0] = np.arange(8) * 2.0
    observed = np.ones((8, thesis21.n_joints), dtype=bool)
    observed[4:7, j] = False
    filled = fill_gaps(uv, observed, thesis21, "previous").uv
    assert np.array_equal(filled[4:7, j, 0], [6.0, 6.0, 6.0])


def test_previous_diff_continues_the_last_change(thesis21):
    uv = _still_hand(thesis21, 8)
    j = thesis21.index("index_tip")
    uv[:, j, 1] = [0, 1, 3, 6, 0, 0, 0, 0]
    observed = np.ones((8, thesis21.n_joints), dtype=bool)
    observed[4:, j] = False
    filled = fill_gaps(uv, observed, thesis21, "previous-diff").uv
    assert np.array_equal(filled[4:, j, 1], [9.0, 12.0, 15.0, 18.0])


def test_intrafinger_reverses_when_the_parent_turns(thesis21):
    uv = _still_hand(thesis21, 4)
    j, parent = thesis21.index("index_tip"), thesis21.index("index_dip")
    uv[:, j, 0] = [10, 12, 14, np.nan]
    uv[:, parent, 0] = [5, 3, 4, 4]        # fell then rose: turned up, while j rises
    observed = np.isfinite(uv).all(axis=-1)
    assert fill_gaps(uv, observed, thesis21, "intrafinger").uv[3, j, 0] == 16
    uv[:, parent, 0] = [3, 5, 4, 4]        # rose then fell: turned against j
    assert fill_gaps(uv, observed, thesis21, "intrafinger").uv[3, j, 0] == 12
    # the interfinger neighbour (middle_tip) stands still: no reversal for method 3
    assert fill_gaps(uv, observed, thesis21, "interfinger").uv[3, j, 0] == 16


def test_intrafinger_rate_adds_the_parents_change(thesis21):
    uv = _still_hand(thesis21, 6)
    j, parent = thesis21.index("ring_dip"), thesis21.index("ring_pip")
    uv[:, j, 0] = [10, 20, 30, 40, 0, 0]
    uv[:, parent, 0] = [0, 1, 2, 3, 4.5, 6]
    observed = np.ones((6, thesis21.n_joints), dtype=bool)
    observed[4:, j] = False
    filled = fill_gaps(uv, observed, thesis21, "intrafinger-rate").uv
    # frame 4: 40 + (3 - 2); frame 5: 41 + (4.5 - 3), the parent's change up to t - 1
    assert np.allclose(filled[4:, j, 0], [41.0, 42.5])


def test_short_history_falls_back_and_is_flagged(thesis21):
    uv = _still_hand(thesis21, 6)
    j = thesis21.index("middle_tip")
    uv[:, j, 0] = np.arange(6) * 3.0
    observed = np.ones((6, thesis21.n_joints), dtype=bool)
    observed[1:3, j] = False
    result = fill_gaps(uv, observed, thesis21, "interfinger")
    # frame 1 has one earlier frame: previous value; frame 2 has two: previous change
    assert np.array_equal(result.uv[1:3, j, 0], [0.0, 0.0])
    flags = result.flags_of(SHORT_HISTORY)
    assert {(f.joint, f.start, f.stop) for f in flags} == {
        ("middle_tip", 1, 2), ("middle_tip", 2, 3)}


def test_missing_first_frame_is_seeded_from_the_palm_and_flagged(thesis21):
    uv = _still_hand(thesis21, 5) + np.arange(5)[:, None, None] * 2.0   # the hand translates
    j = thesis21.index("index_pip")
    observed = np.ones((5, thesis21.n_joints), dtype=bool)
    observed[:2, j] = False
    result = fill_gaps(uv, observed, thesis21, "previous")
    assert np.allclose(result.uv[0, j], uv[0, j])          # carried with the palm
    assert result.filled[:2, j].all()
    assert [(f.joint, f.kind) for f in result.flags_of(LEADING)] == [("index_pip", LEADING)]


def test_a_never_seen_joint_and_a_late_one_both_start_from_a_complete_first_frame(thesis21):
    uv = _still_hand(thesis21, 6)
    late, never = thesis21.index("ring_tip"), thesis21.index("little_tip")
    observed = np.ones((6, thesis21.n_joints), dtype=bool)
    observed[:3, late] = False
    observed[:, never] = False
    result = fill_gaps(uv, observed, thesis21, "previous-diff")
    assert np.isfinite(result.uv).all()
    assert np.allclose(result.uv[:3, late], uv[0, late])     # the hand stands still
