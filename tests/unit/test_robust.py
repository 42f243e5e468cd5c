import warnings

import numpy as np
import pytest

from handdb.robust import nan_median, robust_spread


def test_spread_of_normal_samples_is_their_deviation_despite_outliers_and_gaps():
    rng = np.random.default_rng(3)
    values = rng.normal(40.0, 2.0, (4000, 2))
    values[:200, 0] = 500.0  # outliers a standard deviation would follow
    values[::3, 1] = np.nan
    spread = robust_spread(values)
    assert spread[0] == pytest.approx(2.0 * 1.06, rel=0.05)  # 5 % outliers widen the MAD
    assert spread[1] == pytest.approx(2.0, rel=0.05)
    assert np.std(values[:, 0]) > 50.0


def test_a_column_without_samples_is_nan_and_silent():
    values = np.full((5, 2), np.nan)
    values[:, 0] = [1.0, 2.0, 3.0, 4.0, 9.0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        medians, spread = nan_median(values), robust_spread(values)
    assert medians[0] == 3.0 and np.isnan(medians[1])
    assert spread[0] == pytest.approx(1.4826) and np.isnan(spread[1])


@pytest.mark.parametrize("seed", range(6))
def test_the_median_is_numpys_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(1, 40, size=rng.integers(1, 4)))
    values = rng.normal(10.0, 3.0, shape).round(rng.integers(0, 3))   # ties among samples
    values[rng.random(shape) < rng.uniform(0.0, 0.6)] = np.nan
    if values.ndim > 1:
        values[(slice(None),) * (values.ndim - 1) + (0,)] = np.nan   # columns without samples
    for axis in range(values.ndim):
        for keepdims in (False, True):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                expected = np.nanmedian(values, axis=axis, keepdims=keepdims)
            median = nan_median(values, axis=axis, keepdims=keepdims)
            assert np.shape(median) == np.shape(expected)
            assert np.asarray(median).tobytes() == np.asarray(expected).tobytes()
