"""The running median of bone ratios ignores missing frames and agrees with numpy's."""

import numpy as np
import pytest

from handdb.lengths.estimate import running_median


def _window_nanmedian(values: np.ndarray, frames: int) -> np.ndarray:
    """The definition, one window at a time with :func:`numpy.nanmedian`."""
    half = frames // 2
    out = np.full(values.shape, np.nan)
    for t in range(len(values)):
        window = values[max(0, t - half):t + half + 1]
        for n in range(values.shape[1]):
            finite = window[np.isfinite(window[:, n]), n]
            if np.isfinite(values[t, n]) and 2 * len(finite) >= frames:
                out[t, n] = np.nanmedian(finite)
    return out


@pytest.mark.parametrize("frames", [3, 5, 9])
def test_matches_nanmedian_of_each_window(frames: int) -> None:
    rng = np.random.default_rng(frames)
    values = np.round(rng.lognormal(size=(120, 7)), 2)  # rounded: ties in the windows
    values[rng.uniform(size=values.shape) < 0.35] = np.nan
    got = running_median(values, frames)
    assert np.array_equal(got, _window_nanmedian(values, frames), equal_nan=True)
    assert np.isnan(got[np.isnan(values)]).all()


def test_short_track_is_returned_as_it_is() -> None:
    values = np.array([[1.0, np.nan], [3.0, 2.0]])
    got = running_median(values, 5)
    assert np.array_equal(got, values, equal_nan=True) and got is not values
