import numpy as np
import pytest

from handdb.gapfill import fill_gaps
from handdb.gapfill.palm_frame import EXACT_AFFINE_POINTS, palm_motion
from handdb.gapfill.rigid import palm_joints
from handdb.gapfill.transfer import apply_affine, fit_maps
from handdb.synthetic.clips import synthesize_clip

NOISE_PX = 3.0
NOISE_SEEDS = range(3)
#: The knuckles hidden from the middle of the clip on, as in the thesis's Table 4.2.
HIDDEN = ("middle_mcp", "ring_mcp", "little_mcp")
LAST_SEEN = 50


@pytest.fixture(scope="module")
def waving_hand():
    return synthesize_clip("wave", 100, seed=2)


def _hide_knuckles(n_frames, skeleton):
    observed = np.ones((n_frames, skeleton.n_joints), dtype=bool)
    observed[LAST_SEEN:, [skeleton.index(name) for name in HIDDEN]] = False
    return observed


def test_frames_showing_three_palm_points_are_not_fitted_when_others_show_more(
        waving_hand, mediapipe):
    observed = _hide_knuckles(len(waving_hand.uv), mediapipe)
    shown = (observed & palm_joints(mediapipe)).sum(axis=1)
    assert shown[LAST_SEEN:].max() == EXACT_AFFINE_POINTS < shown[:LAST_SEEN].min()
    uv = np.where(observed[..., None], waving_hand.uv, np.nan)
    motion = palm_motion(uv, ~observed, mediapipe)
    assert motion.fitted[:LAST_SEEN].all() and not motion.fitted[LAST_SEEN:].any()


def test_hidden_knuckles_beat_an_exact_fit_to_three_noisy_palm_points(waving_hand, mediapipe):
    truth = waving_hand.uv
    observed = _hide_knuckles(len(truth), mediapipe)
    hidden = [mediapipe.index(name) for name in HIDDEN]
    shown = np.flatnonzero(palm_joints(mediapipe) & observed[-1])
    filled_error, exact_error = 0.0, 0.0
    for seed in NOISE_SEEDS:
        noisy = truth + np.random.default_rng(seed).normal(0.0, NOISE_PX, truth.shape)
        filled = fill_gaps(noisy, observed, mediapipe).uv
        filled_error += np.sum((filled - truth)[LAST_SEEN:, hidden] ** 2)
        # The alternative: each frame's affine map through its three noisy palm points, from
        # the palm as last seen whole, carrying the knuckles from there.
        later = noisy[LAST_SEEN:]
        source = np.broadcast_to(noisy[LAST_SEEN - 1], later.shape)
        linear, offset, _ = fit_maps(source[:, shown], later[:, shown],
                                     np.ones((len(later), shown.size), dtype=bool))
        carried = apply_affine(linear, offset, source[:, hidden])
        exact_error += np.sum((carried - truth[LAST_SEEN:, hidden]) ** 2)
    assert filled_error < exact_error
