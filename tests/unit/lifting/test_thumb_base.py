"""The thumb base's height over the rigid palm: per frame, and one for the whole clip."""

import math

import numpy as np
import pytest

from handdb.lifting.thumb_base import (
    HEIGHT_GRID,
    SPREAD_GRID,
    _mixture_log_likelihood,
    clip_heights,
    outlier_density,
    plane_heights,
)

#: Wrist, index MCP, little MCP and two more knuckles of a right palm in the plane z = 0,
#: seen from its palmar side along +z (camera frame: x right, y down).
PALM = np.array([[0.0, 0.0, 0.0], [-20.0, -80.0, 0.0], [30.0, -70.0, 0.0], [0.0, -82.0, 0.0],
                 [15.0, -78.0, 0.0]])
CORNERS = np.array([0, 1, 2])


@pytest.mark.parametrize(("hand", "handedness"), [("right", 1.0), ("left", -1.0)])
def test_heights_are_palmar_positive_for_either_hand(hand, handedness):
    palm = np.broadcast_to(PALM, (3, 2, 5, 3)).copy()
    options = np.zeros((2, 3, 2, 3))
    options[0, ..., 2], options[1, ..., 2] = 12.0, -12.0
    palmar = np.sign(np.cross(PALM[1] - PALM[0], PALM[2] - PALM[0])[2]) * handedness
    heights = plane_heights(palm, options, CORNERS, handedness)
    np.testing.assert_allclose(heights[0], 12.0 * palmar)
    np.testing.assert_allclose(heights[1], -12.0 * palmar)


def test_a_palm_with_too_few_joints_has_no_height():
    palm = np.broadcast_to(PALM, (1, 2, 5, 3)).copy()
    palm[0, 0, 2:] = np.nan
    heights = plane_heights(palm, np.zeros((2, 1, 2, 3)), CORNERS, 1.0)
    assert np.isnan(heights[:, 0, 0]).all() and np.isfinite(heights[:, 0, 1]).all()


@pytest.mark.parametrize("truth", [0.0, 0.2, 0.3])
def test_the_clip_height_is_the_one_every_frame_offers(truth):
    rng = np.random.default_rng(2)
    n_frames = 300
    right = truth + rng.normal(0.0, 0.01, n_frames)
    wrong = rng.uniform(-0.45, 0.45, n_frames)
    first = rng.random(n_frames) < 0.5
    heights = np.stack([np.where(first, right, wrong), np.where(first, wrong, right)])
    modes, spread = clip_heights(heights)
    assert abs(modes[0] - truth) <= 2 * (HEIGHT_GRID[1] - HEIGHT_GRID[0])
    assert spread < 0.03


def _plain_log_likelihood(heights, grid, spreads, floor):
    """The mixture's log-likelihood term by term, every exponential taken, ``(H, S)``."""
    out = np.empty((len(grid), len(spreads)))
    for i, centre in enumerate(grid):
        for s, sd in enumerate(spreads):
            log_norm = math.log(sd * math.sqrt(2.0 * math.pi))
            total = 0.0
            for above, below in zip((heights[0] - centre) / sd, (heights[1] - centre) / sd,
                                    strict=True):
                density = 0.5 * (math.exp(-0.5 * above * above - log_norm)
                                 + math.exp(-0.5 * below * below - log_norm))
                total += math.log(density + floor)
            out[i, s] = total
    return out


@pytest.mark.parametrize("floor", [outlier_density(), 1e-300, 0.0])
def test_skipping_negligible_densities_leaves_the_likelihood_unchanged(floor):
    rng = np.random.default_rng(5)
    heights = np.stack([rng.normal(0.1, 0.02, 40), rng.uniform(-0.6, 0.6, 40)])
    grid, spreads = HEIGHT_GRID[::8], SPREAD_GRID
    out = np.empty((len(grid), len(spreads)))
    _mixture_log_likelihood(heights, grid, spreads, floor, out)
    expected = _plain_log_likelihood(heights, grid, spreads, floor)
    np.testing.assert_array_equal(out, expected)
