"""The depth comparison chart: bars as tall as their values, one colour per method."""

from io import BytesIO

import numpy as np
import pytest
from PIL import Image

from handdb.validation.chart import CHART_PIXELS, METHOD_RGB, draw_comparison_chart, nice_step

JOINTS = ("wrist", "thumb_cmc", "thumb_mcp")


def _pixels_of(png: bytes, rgb: tuple[int, int, int]) -> int:
    image = np.asarray(Image.open(BytesIO(png)).convert("RGB"))
    assert image.shape == (CHART_PIXELS[1], CHART_PIXELS[0], 3)
    return int((image == rgb).all(axis=-1).sum())


@pytest.mark.parametrize(("top", "step"), [(7.3, 2.0), (0.42, 0.1), (100.0, 20.0), (0.0, 1.0)])
def test_ticks_are_round(top, step):
    assert nice_step(top) == pytest.approx(step)


def test_a_bar_twice_as_high_covers_twice_the_pixels():
    heights = np.array([[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]])
    png = draw_comparison_chart("c1", JOINTS, ["low", "high"], heights, "mean |dZ| (mm)")
    low, high = _pixels_of(png, METHOD_RGB[0]), _pixels_of(png, METHOD_RGB[1])
    assert 1.7 < high / low < 2.1


def test_a_missing_value_draws_no_bar():
    whole = np.array([[1.0, 2.0, 3.0]])
    gap = np.array([[1.0, np.nan, 3.0]])
    drawn = [_pixels_of(draw_comparison_chart("c1", JOINTS, ["m"], h, "mm"), METHOD_RGB[0])
             for h in (whole, gap)]
    assert drawn[1] < drawn[0]
