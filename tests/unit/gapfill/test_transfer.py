import numpy as np
import pytest

from handdb.gapfill.transfer import (
    AFFINE,
    NO_MAP,
    SIMILARITY,
    TRANSLATION,
    apply_affine,
    fit_maps,
    fit_maps_from_shape,
)


def _random_affine(rng, n):
    return rng.normal(size=(n, 2, 2)) + 2 * np.eye(2), rng.normal(size=(n, 2)) * 50


def test_fit_maps_recovers_affine_maps_from_three_or_more_points():
    rng = np.random.default_rng(0)
    pentagon = np.stack([np.cos(np.arange(5) * 1.2566), np.sin(np.arange(5) * 1.2566)], -1)
    source = pentagon * 30 + rng.normal(size=(200, 5, 2))
    linear, offset = _random_affine(rng, 200)
    target = apply_affine(linear, offset, source)
    weights = rng.random((200, 5)) < 0.8
    weights[:, :3] = True
    fitted_linear, fitted_offset, kind = fit_maps(source, np.where(weights[..., None], target,
                                                                   np.nan), weights)
    assert (kind == AFFINE).all()
    assert np.allclose(fitted_linear, linear) and np.allclose(fitted_offset, offset)


def test_fit_maps_falls_back_by_the_number_of_points():
    rng = np.random.default_rng(1)
    source = rng.normal(size=(4, 3, 2))
    target = source * 2.0 + 7.0
    weights = np.array([[True, True, True], [True, True, False], [False, True, False],
                        [False, False, False]])
    linear, offset, kind = fit_maps(source, target, weights)
    assert kind.tolist() == [AFFINE, SIMILARITY, TRANSLATION, NO_MAP]
    assert np.allclose(linear[:2], 2.0 * np.eye(2)) and np.allclose(offset[:2], 7.0)
    assert np.isnan(offset[3]).all()


@pytest.mark.parametrize(("n_points", "hidden"), [(6, 0.0), (6, 0.2), (3, 0.5), (1, 0.5)])
@pytest.mark.parametrize("affine", [True, False])
def test_maps_from_one_shape_equal_the_maps_from_the_repeated_shape(n_points, hidden, affine):
    rng = np.random.default_rng(n_points)
    shape = rng.normal(size=(n_points, 2))
    target = rng.normal(size=(300, n_points, 2)) * 100
    weights = rng.random((300, n_points)) >= hidden
    target[~weights] = np.nan
    repeated = fit_maps(np.broadcast_to(shape, target.shape), target, weights, affine=affine)
    from_shape = fit_maps_from_shape(shape, target, weights, affine=affine)
    for expected, got in zip(repeated, from_shape, strict=True):
        assert np.allclose(got, expected, rtol=1e-9, atol=1e-9, equal_nan=True)
