import itertools

import numpy as np
import pytest

from handdb.lifting.temporal import acceleration_spread, sign_posterior, smooth_scale


def both_signs(values):
    """``(T, K, D)`` values under the positive sign to ``(T, K, 2, D)``, mirrored."""
    return np.stack([values, -values], axis=2)


def brute_force_posterior(log_odds, values, spread):
    """Log-odds of the positive sign per frame, by enumerating every sign sequence.

    ``values`` is ``(T, 2, D)``: the value under the positive and the negative sign.
    """
    n = len(log_odds)
    plus, total = np.zeros(n), 0.0
    for seq in itertools.product((0, 1), repeat=n):
        signs = 1.0 - 2.0 * np.array(seq)
        signed = values[np.arange(n), seq]
        score = 0.5 * np.sum(signs * log_odds)
        score -= np.sum(np.diff(signed, 2, axis=0) ** 2) / (2.0 * spread**2)
        weight = np.exp(score)
        total += weight
        plus += weight * (signs > 0)
    return np.log(plus) - np.log(total - plus)


@pytest.mark.parametrize("n_frames", [1, 2, 3, 5, 8])
def test_sign_posterior_matches_enumeration(n_frames):
    rng = np.random.default_rng(n_frames)
    log_odds = rng.normal(scale=2.0, size=n_frames)
    values = rng.normal(size=(n_frames, 2, 3))    # near and far solutions differ
    spread = 1.3
    got = sign_posterior(log_odds[:, None], values[:, None], np.array([spread]))[:, 0]
    np.testing.assert_allclose(got, brute_force_posterior(log_odds, values, spread),
                               atol=1e-9)


def bridged_posterior(log_odds, values, spread, frames):
    """:func:`brute_force_posterior` over the observed ``frames`` of a longer clip.

    Across dropped frames the second difference is that of the mean velocities over the
    two steps, its variance the spread's times half their summed length.
    """
    n = len(frames)
    plus, total = np.zeros(n), 0.0
    for seq in itertools.product((0, 1), repeat=n):
        signs = 1.0 - 2.0 * np.array(seq)
        signed = values[frames, seq]
        steps = np.diff(frames)[:, None]
        acceleration = np.diff(np.diff(signed, axis=0) / steps, axis=0)
        width = 0.5 * (steps[1:] + steps[:-1])
        unit = width == 1.0
        acceleration = np.where(unit, np.diff(signed, 2, axis=0), acceleration)
        score = 0.5 * np.sum(signs * log_odds[frames])
        score -= np.sum(acceleration**2 / width) / (2.0 * spread**2)
        weight = np.exp(score)
        total += weight
        plus += weight * (signs > 0)
    return np.log(plus) - np.log(total - plus)


def test_the_chain_bridges_dropped_frames_by_the_observed_ones():
    rng = np.random.default_rng(3)
    log_odds = rng.normal(scale=2.0, size=12)
    values = rng.normal(size=(12, 2, 3))
    frames = np.array([0, 1, 2, 5, 6, 7, 8, 10, 11])
    dropped = np.setdiff1d(np.arange(12), frames)
    values[dropped] = np.nan
    spread = 1.3
    got = sign_posterior(log_odds[:, None], values[:, None], np.array([spread]))[:, 0]
    np.testing.assert_allclose(got[frames],
                               bridged_posterior(log_odds, values, spread, frames), atol=1e-9)
    np.testing.assert_allclose(got[dropped], log_odds[dropped])


def test_dropped_frames_do_not_widen_the_acceleration_spread():
    depth = np.linspace(5.0, 15.0, 30)[:, None, None]
    gapped = depth.copy()
    gapped[10:13] = np.nan
    floor = np.array([0.1])
    np.testing.assert_allclose(acceleration_spread(gapped, floor),
                               acceleration_spread(depth, floor))


def test_a_steep_bone_keeps_its_sign_through_uninformative_frames():
    # evidence only at the start; the bone never nears the image plane afterwards
    log_odds = np.zeros(50)
    log_odds[0] = 3.0
    depth = np.full((50, 1, 1), 20.0)
    posterior = sign_posterior(log_odds[:, None], both_signs(depth),
                               acceleration_spread(depth, np.array([1.0])))
    assert np.all(posterior[:, 0] > 2.0)


def test_a_bone_moving_through_the_image_plane_keeps_going():
    # |dZ| falls to zero and rises again at the same rate: the motion goes on through the
    # image plane rather than bouncing back, so the sign flips at the crossing even though
    # only the first frame says which sign the bone starts with
    log_odds = np.zeros(41)
    log_odds[0] = 3.0
    depth = np.abs(np.linspace(20.0, -20.0, 41))[:, None, None]
    posterior = sign_posterior(log_odds[:, None], both_signs(depth),
                               acceleration_spread(depth, np.array([1.0])))
    assert np.all(posterior[:20, 0] > 0) and np.all(posterior[21:, 0] < 0)


def test_a_bone_nearing_the_image_plane_turns_back():
    log_odds = np.zeros(41)
    log_odds[0] = 3.0
    depth = (20.0 - 15.0 * np.sin(np.linspace(0.0, np.pi, 41)))[:, None, None]
    posterior = sign_posterior(log_odds[:, None], both_signs(depth),
                               acceleration_spread(depth, np.array([1.0])))
    assert np.all(posterior[:, 0] > 1.0)


def test_smooth_scale_ignores_an_outlier_frame_and_fills_gaps():
    bounds = np.full(100, 2.0)
    bounds[40] = 9.0
    bounds[60:63] = np.nan
    scale = smooth_scale(bounds)
    np.testing.assert_allclose(scale, 2.0, atol=1e-9)


def test_certain_frames_that_disagree_still_give_finite_posteriors():
    log_odds = np.array([[np.inf], [-np.inf], [np.inf]])
    depth = np.full((3, 1, 1), 100.0)
    posterior = sign_posterior(log_odds, both_signs(depth), np.array([1.0]))
    # a flip costs far more than any frame's evidence: two certain frames outvote one
    assert np.all(np.isfinite(posterior)) and np.all(posterior > 0)
