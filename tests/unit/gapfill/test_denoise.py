"""Detector jitter: measured from the clip, smoothed away before filling, observed points kept."""

import numpy as np
import pytest

from handdb.denoise import denoise, noise_level
from handdb.gapfill import fill_gaps
from handdb.gapfill.masks import random_gaps_mask

NOISE_PX = 3.0


@pytest.fixture(scope="module")
def noisy(rapid_clip):
    rng = np.random.default_rng(0)
    return rapid_clip.uv + rng.normal(0.0, NOISE_PX, rapid_clip.uv.shape)


def test_the_noise_level_is_measured_from_the_tracks(rapid_clip, noisy):
    nothing_missing = np.zeros(rapid_clip.uv.shape[:2], dtype=bool)
    assert noise_level(noisy, nothing_missing) == pytest.approx(NOISE_PX, rel=0.15)
    assert noise_level(rapid_clip.uv, nothing_missing) < NOISE_PX / 5


def test_smoothing_brings_noisy_tracks_nearer_the_truth(rapid_clip, noisy):
    nothing_missing = np.zeros(rapid_clip.uv.shape[:2], dtype=bool)
    smoothed, half = denoise(noisy, nothing_missing)
    assert half > 0
    error = np.sqrt(np.mean((smoothed - rapid_clip.uv) ** 2))
    assert error < 0.9 * np.sqrt(np.mean((noisy - rapid_clip.uv) ** 2))


def test_clean_tracks_are_left_as_they_are(rapid_clip):
    missing = np.zeros(rapid_clip.uv.shape[:2], dtype=bool)
    missing[100:140, 8] = True
    smoothed, half = denoise(rapid_clip.uv, missing)
    assert half == 0
    assert smoothed is rapid_clip.uv


def test_missing_points_and_short_runs_are_not_smoothed(noisy):
    missing = np.zeros(noisy.shape[:2], dtype=bool)
    missing[:, 3] = True
    missing[::3, 5] = True
    tracks = np.where(missing[..., None], np.nan, noisy)
    smoothed, half = denoise(tracks, missing)
    assert half > 0
    np.testing.assert_array_equal(smoothed[:, 5], tracks[:, 5])
    assert np.isnan(smoothed[missing]).all()
    assert not np.allclose(smoothed[:, 4], tracks[:, 4])


def test_auto_fills_from_smoothed_tracks_and_returns_the_observed_points(rapid_clip, noisy,
                                                                          mediapipe):
    squares = {True: 0.0, False: 0.0}
    for seed in range(4):
        observed = ~random_gaps_mask(*rapid_clip.uv.shape[:2], seed=seed)
        for smooth in squares:
            filled = fill_gaps(noisy, observed, mediapipe, "auto", smooth=smooth).uv
            np.testing.assert_array_equal(filled[observed], noisy[observed])
            squares[smooth] += np.sum((filled - rapid_clip.uv)[~observed] ** 2)
    assert squares[True] < 0.95 * squares[False]
