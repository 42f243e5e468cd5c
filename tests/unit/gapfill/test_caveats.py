"""What a gap fill could not know is read from its arrays, so a fill read back from the
store (which keeps no notes) is flagged with the same reasons as the fill that made it."""

from dataclasses import replace

import numpy as np

from handdb.gapfill import fill_gaps
from handdb.gapfill.caveats import fill_caveats, never_detected
from handdb.hand.skeletons import load_skeleton
from handdb.synthetic import synthesize_clip

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
