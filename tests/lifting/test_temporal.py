import itertools

import numpy as np
import pytest

from handdb.lifting.temporal import flip_costs, sign_posterior, smooth_scale


def brute_force_posterior(log_odds, flip_cost):
    """Every sign sequence of one chain with its unnormalised probability."""
    n = len(log_odds)
    for seq in itertools.product((1, -1), repeat=n):
        score = sum(0.5 * s * e for s, e in zip(seq, log_odds, strict=True))
        score -= sum(flip_cost[t] for t in range(1, n) if seq[t] != seq[t - 1])
        yield seq, np.exp(score)


@pytest.mark.parametrize("n_frames", [1, 2, 5, 8])
def test_sign_posterior_matches_enumeration(n_frames):
    rng = np.random.default_rng(n_frames)
    log_odds = rng.normal(scale=2.0, size=n_frames)
    cost = np.abs(rng.normal(scale=2.0, size=n_frames))
    cost[0] = 0.0
    plus = np.zeros(n_frames)
    total = 0.0
    for seq, w in brute_force_posterior(log_odds, cost):
        total += w
        plus += w * (np.array(seq) > 0)
    expected = np.log(plus) - np.log(total - plus)
    got = sign_posterior(log_odds[:, None], cost[:, None])[:, 0]
    np.testing.assert_allclose(got, expected, atol=1e-9)


def test_a_steep_bone_keeps_its_sign_through_uninformative_frames():
    # evidence only at the ends; the bone never nears the image plane in between
    log_odds = np.zeros(50)
    log_odds[0] = 3.0
    magnitude = np.full((50, 1), 20.0)
    posterior = sign_posterior(log_odds[:, None], flip_costs(magnitude, np.array([1.0])))
    assert np.all(posterior[:, 0] > 2.0)


def test_a_bone_crossing_the_image_plane_may_flip():
    log_odds = np.r_[np.full(20, 2.0), np.full(20, -2.0)]
    magnitude = np.abs(np.linspace(-20, 20, 40))[:, None]     # passes through zero
    posterior = sign_posterior(log_odds[:, None], flip_costs(magnitude, np.array([1.0])))
    assert np.all(posterior[:15, 0] > 0) and np.all(posterior[25:, 0] < 0)


def test_smooth_scale_ignores_an_outlier_frame_and_fills_gaps():
    bounds = np.full(100, 2.0)
    bounds[40] = 9.0
    bounds[60:63] = np.nan
    scale = smooth_scale(bounds)
    np.testing.assert_allclose(scale, 2.0, atol=1e-9)


def test_certain_frames_that_disagree_still_give_finite_posteriors():
    log_odds = np.array([[np.inf], [-np.inf], [np.inf]])
    posterior = sign_posterior(log_odds, np.full((3, 1), 1e4))
    # a flip costs far more than any frame's evidence: two certain frames outvote one
    assert np.all(np.isfinite(posterior)) and np.all(posterior > 0)
