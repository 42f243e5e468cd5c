"""What a gap fill could not know is read from its arrays, so a fill read back from the
store (which keeps no notes) is flagged with the same reasons as the fill that made it."""

from dataclasses import replace

import numpy as np
import pytest

from handdb.gapfill import fill_gaps
from handdb.gapfill.caveats import caveat_rows, fill_caveats, never_detected
from handdb.hand.skeletons import load_skeleton
from handdb.synthetic import synthesize_clip
from tests.support.benchmarks import benchmark_module

SKELETON = load_skeleton("mediapipe21")


def test_a_joint_never_detected_is_said_with_or_without_the_fills_notes():
    clip = synthesize_clip("wave", 40, seed=3)
    observed = np.ones(clip.uv.shape[:2], dtype=bool)
    observed[:, SKELETON.index("little_tip")] = False
    observed[:2] = False
    result = fill_gaps(clip.uv, observed, SKELETON)
    assert np.flatnonzero(never_detected(result)).tolist() == [SKELETON.index("little_tip")]
    caveats = fill_caveats(result, SKELETON)
    assert any(c.startswith("little_tip never detected") for c in caveats)
    assert any("observe no point" in c for c in caveats)
    assert fill_caveats(replace(result, flags=()), SKELETON) == caveats


def test_a_fully_observed_clip_has_no_caveat():
    clip = synthesize_clip("wave", 20, seed=3)
    result = fill_gaps(clip.uv, np.ones(clip.uv.shape[:2], dtype=bool), SKELETON)
    assert fill_caveats(result, SKELETON) == ()


def test_a_joint_one_segment_never_shows_is_said_and_its_rows_marked():
    """MediaPipe's real landmarks, hand 0: frames 30-40 empty split the clip (longer than
    ``SHORT_GAP``), and the little fingertip is hidden after them. The second segment
    places it by the hand model though the clip detects it: a caveat names the frames."""
    with benchmark_module("gapfill_datasets") as datasets:
        cases = datasets.mediapipe_cases()
        if not cases:
            pytest.skip(f"shared data not present: {datasets.MEDIAPIPE}")
    case = cases[0]
    tip = case.skeleton.index("little_tip")
    observed = np.isfinite(case.uv).all(axis=-1)
    observed[30:41] = False
    observed[41:, tip] = False
    result = fill_gaps(case.uv, observed, case.skeleton)
    assert not never_detected(result).any()
    assert (result.fill_method[41:, tip] == "rest-pose").all()
    caveats = fill_caveats(result, case.skeleton)
    assert ("little_tip detected in part of the clip only: placed by the hand model "
            "(rest-pose) in 23 of 64 frames (41-63)") in caveats[0]
    assert caveats[1].startswith("11 of 64 frames (30-40) observe no point")
    rows = caveat_rows(result)
    expected = np.zeros_like(rows)
    expected[30:41] = True
    expected[41:, tip] = True
    np.testing.assert_array_equal(rows, expected)
    assert fill_caveats(replace(result, flags=()), case.skeleton) == caveats
