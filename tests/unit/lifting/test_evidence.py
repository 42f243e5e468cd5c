import numpy as np
import pytest

from handdb.lifting.evidence import Evidence, autocorrelation_time


def ar1(phi, n_frames, seed):
    """An AR(1) series ``x_t = phi x_(t-1) + e_t``: its autocorrelation time is
    ``(1 + phi) / (1 - phi)``."""
    noise = np.random.default_rng(seed).normal(size=n_frames)
    x = np.empty(n_frames)
    x[0] = noise[0] / np.sqrt(1 - phi**2)
    for t in range(1, n_frames):
        x[t] = phi * x[t - 1] + noise[t]
    return x


@pytest.mark.parametrize("phi", [0.0, 0.5, 0.9])
def test_autocorrelation_time_of_an_ar1_series(phi):
    tau = autocorrelation_time(ar1(phi, 20000, 3)[:, None])[0]
    assert tau == pytest.approx(max((1 + phi) / (1 - phi), 1.0), rel=0.2)


def test_a_constant_series_a_single_frame_or_none_counts_every_frame():
    assert autocorrelation_time(np.full((50, 2), 3.0)).tolist() == [1.0, 1.0]
    assert autocorrelation_time(np.array([[2.0]])).tolist() == [1.0]
    assert autocorrelation_time(np.empty((0, 3))).tolist() == [1.0, 1.0, 1.0]


def test_repeating_every_frame_adds_no_evidence():
    frames = np.column_stack([ar1(0.3, 400, 5) + 0.2, ar1(0.0, 400, 6) - 0.1])
    once, repeated = Evidence(frames, 1.5), Evidence(np.repeat(frames, 8, axis=0), 1.5)
    assert repeated.total() - 1.5 == pytest.approx(8 * (once.total() - 1.5))
    assert repeated.calibrated() == pytest.approx(once.calibrated(), rel=0.25)


def test_a_log_ratio_is_the_difference_of_its_terms():
    rng = np.random.default_rng(0)
    a, b = Evidence(rng.normal(size=(30, 3)), 2.0), Evidence(rng.normal(size=(30, 3)), -1.0)
    ratio = a - b
    assert ratio.total() == pytest.approx(a.total() - b.total())
    assert (-ratio).calibrated() == pytest.approx(-ratio.calibrated())
