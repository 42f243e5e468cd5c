"""Where the hand model places a joint never observed, on MediaPipe's real landmarks.

One rule says which frames can place it (:func:`~handdb.gapfill.rigid.placeable_frames`:
those showing three palm points), and both the placement and the refusal of a clip that
never shows a palm follow it; in a placeable frame the rest pose is fitted to every joint
the frame observes. The landmarks are those of ``benchmarks/gapfill_datasets.py``.
"""

import numpy as np
import pytest

from handdb.errors import GapFillError
from handdb.gapfill import fill_gaps
from handdb.gapfill.rigid import palm_joints
from tests.support.benchmarks import benchmark_module

#: Frames of the real clip that observe the wrist alone.
WRIST_ONLY = slice(20, 24)


@pytest.fixture(scope="module")
def hands():
    """MediaPipe's two real hands (``Case`` of ``benchmarks/gapfill_datasets.py``)."""
    with benchmark_module("gapfill_datasets") as module:
        cases = module.mediapipe_cases()
        if not cases:
            pytest.skip(f"shared data not present: {module.MEDIAPIPE}")
        yield cases


def _hand_size(uv):
    return float(np.nanmedian(np.ptp(uv, axis=1).max(axis=-1)))


def _error(result, case, frames, joint):
    return np.linalg.norm(result.uv[frames, joint] - case.uv[frames, joint], axis=-1)


@pytest.mark.parametrize("hand", [0, 1])
def test_a_frame_observing_one_point_is_bridged_not_placed_on_it(hands, hand):
    """A frame that sees only the wrist gives the rest pose a translation, no size: the
    never-found fingertip would land a pixel from the wrist. It is bridged from the
    frames around, as close as where those place it."""
    case = hands[hand]
    tip = case.skeleton.index("little_tip")
    observed = np.isfinite(case.uv).all(axis=-1)
    observed[:, tip] = False
    observed[WRIST_ONLY] = False
    observed[WRIST_ONLY, case.skeleton.root] = True
    result = fill_gaps(case.uv, observed, case.skeleton, "auto")
    assert (result.fill_method[:, tip] == "rest-pose").all()
    wrist = case.uv[WRIST_ONLY, case.skeleton.root]
    reach = np.linalg.norm(case.uv[WRIST_ONLY, tip] - wrist, axis=-1)
    placed = np.linalg.norm(result.uv[WRIST_ONLY, tip] - wrist, axis=-1)
    assert (placed > 0.5 * reach).all()
    around = np.r_[WRIST_ONLY.start - 4:WRIST_ONLY.start, WRIST_ONLY.stop:WRIST_ONLY.stop + 4]
    assert (_error(result, case, WRIST_ONLY, tip).max()
            < 2 * _error(result, case, around, tip).max() + 0.05 * _hand_size(case.uv))


@pytest.mark.parametrize("hand", [0, 1])
def test_a_fingertip_is_placed_from_its_own_finger_as_well_as_the_palm(hands, hand):
    """Fitted to the palm alone the rest pose puts a bent finger's tip where an open
    hand's would be; fitted to every observed joint, its own finger's pull it towards the
    finger. Mean over three fingertips, each never found in its own clip."""
    case = hands[hand]
    every = np.arange(len(case.uv))
    errors = []
    for joint in ("thumb_tip", "index_tip", "little_tip"):
        index = case.skeleton.index(joint)
        observed = np.isfinite(case.uv).all(axis=-1)
        observed[:, index] = False
        palm_only = observed & palm_joints(case.skeleton)
        errors.append([_error(fill_gaps(case.uv, seen, case.skeleton, "auto"), case, every,
                              index).mean() for seen in (observed, palm_only)])
    with_fingers, from_palm = np.mean(errors, axis=0)
    assert with_fingers < 0.75 * from_palm
    assert with_fingers < 0.35 * _hand_size(case.uv)


def test_a_clip_that_never_shows_three_palm_points_is_refused(hands):
    """Its frames observe the wrist, one knuckle and every finger point: no palm to place
    the hand model on, though the fingers would give a fit."""
    case = hands[0]
    observed = np.isfinite(case.uv).all(axis=-1) & ~palm_joints(case.skeleton)
    observed[:, [case.skeleton.root, case.skeleton.index("index_mcp")]] = True
    observed[:, case.skeleton.index("little_tip")] = False
    with pytest.raises(GapFillError, match="no frame observes 3 of those"):
        fill_gaps(case.uv, observed, case.skeleton, "auto")
