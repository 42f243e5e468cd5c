"""The Qualisys glove of ../shared/data/real-tools: skin markers named for the joints they
sit nearest, which skip joints, so some bones no marker pair measures."""

import numpy as np
import pytest

from handdb.hand.model import build_hand_model
from handdb.markers.calibration import (
    REACH_LIMIT_MM,
    bounded_reach,
    calibrate,
    calibrate_reachable,
)
from handdb.validation.plausibility import length_bounds_mm
from tests.support.benchmarks import benchmark_module

#: Frames of the recording calibrated (every third), from its middle.
FIRST, N_FRAMES = 855, 100


@pytest.fixture(scope="module")
def glove_track():
    """``(100, 21, 3)`` mm: the glove's 13 hand markers on the ``mediapipe21`` joints."""
    with benchmark_module("gapfill_datasets") as datasets:
        if not datasets.GLOVE.is_file():
            pytest.skip(f"shared data not present: {datasets.GLOVE}")
        recording = datasets.glove_markers()[::datasets.GLOVE_STEP]
        joints = [joint for _, joint, *_ in datasets.GLOVE_MARKERS]
    model = build_hand_model("right")
    markers = np.full((N_FRAMES, model.n_joints, 3), np.nan)
    markers[:, [model.skeleton.index(j) for j in joints]] = recording[FIRST:FIRST + N_FRAMES]
    return markers


@pytest.mark.slow
def test_a_bone_no_marker_pair_measures_is_not_traded_away(glove_track):
    # the little finger's PIP is not marked: LM once traded its middle phalanx to 0 mm and
    # stretched the proximal one to 112 mm for marker error
    model = build_hand_model("right")
    lengths = calibrate(model, glove_track).model.bone_lengths
    low = length_bounds_mm(model.skeleton)[model.skeleton.bones[:, 1], 0]
    bounded = np.isfinite(low)
    assert bounded.sum() >= 15
    slack = 0.5  # mm: the bound is a steep penalty, not a hard constraint
    assert np.all(lengths[bounded] >= low[bounded] - slack)
    little = model.skeleton.bone_names.index("little_pip")
    assert lengths[little] < 80.0


@pytest.mark.slow
def test_the_calibrated_glove_is_a_hand_the_bounded_tracker_can_pose(glove_track):
    # with its poses free of the bounds, the calibration buys the glove's skin markers with
    # knuckles twisted hundreds of degrees: fitted within the bounds, its own frames end far
    # from their markers (the wrist marker about 80 mm)
    # (the reach's refit restarts no finger, so it stays above the 1.4 mm the full fit of
    # these frames reaches)
    model = build_hand_model("right")
    free = bounded_reach(calibrate(model, glove_track), glove_track)
    assert free > REACH_LIMIT_MM
    assert bounded_reach(calibrate_reachable(model, glove_track), glove_track) < free
