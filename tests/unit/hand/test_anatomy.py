"""The anatomy tables: every joint axis of the model has a range, with a source."""

import numpy as np
import pytest

from handdb.hand import anatomy
from handdb.hand.model import build_hand_model
from handdb.hand.skeletons import load_skeleton


def test_every_axis_of_the_model_has_an_active_range():
    model = build_hand_model()
    for name in model.dof_names[6:]:
        joint, axis = name.split(".")
        finger, role = joint.split("_")
        lower, upper = anatomy.RANGE_OF_MOTION_DEG[(finger, role, axis)]
        assert lower <= 0.0 < upper


def test_clinical_norms_are_the_ones_kept():
    rom = anatomy.RANGE_OF_MOTION_DEG
    assert rom[("index", "mcp", "flexion")] == (-20.0, 90.0)
    assert rom[("ring", "pip", "flexion")] == (0.0, 110.0)
    assert rom[("thumb", "ip", "flexion")] == (-15.0, 80.0)
    assert anatomy.DIP_PIP_COUPLING == pytest.approx(2.0 / 3.0)


def test_hand_length_proportions_follow_the_mean_hand_and_leave_unknown_bones_out():
    skeleton = load_skeleton("mediapipe21")
    proportions = anatomy.hand_length_proportions(skeleton)
    index = [skeleton.index(f"index_{j}") for j in ("pip", "dip", "tip")]
    assert proportions[index] == pytest.approx(anatomy.segment_proportions("index")[1:])
    assert proportions[index].sum() == pytest.approx(sum(anatomy.BUCHHOLZ_1992["index"][1:]))
    assert np.isnan(proportions[skeleton.index("thumb_cmc")])
    assert np.isnan(proportions[skeleton.root])
    middle = [skeleton.index(f"middle_{j}") for j in ("mcp", "pip", "dip", "tip")]
    assert proportions[middle].sum() == pytest.approx(1.0)
