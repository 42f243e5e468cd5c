"""The chart's PNG writer: Pillow decodes its files to the very pixels written."""

import io

import numpy as np
import pytest
from PIL import Image

from handdb.validation.png import PNG_SIGNATURE, rgb_png


def _decoded(png: bytes) -> np.ndarray:
    image = Image.open(io.BytesIO(png))
    assert image.mode == "RGB"
    return np.asarray(image)


@pytest.mark.parametrize("shape", [(1, 1, 3), (7, 5, 3), (40, 33, 3)])
def test_any_pixels_decode_unchanged(shape):
    pixels = np.random.default_rng(sum(shape)).integers(0, 256, shape, dtype=np.uint8)
    png = rgb_png(pixels, level=3)
    assert png.startswith(PNG_SIGNATURE)
    np.testing.assert_array_equal(_decoded(png), pixels)


def test_rows_that_wrap_below_zero_decode_unchanged():
    pixels = np.zeros((4, 6, 3), dtype=np.uint8)
    pixels[::2] = 255                                  # each row minus the one above: -255
    np.testing.assert_array_equal(_decoded(rgb_png(pixels, level=9)), pixels)


def test_flat_colour_compresses():
    pixels = np.full((400, 1200, 3), 255, dtype=np.uint8)
    assert len(rgb_png(pixels, level=3)) < pixels.nbytes / 100


@pytest.mark.parametrize("pixels", [np.zeros((4, 4), np.uint8), np.zeros((4, 4, 4), np.uint8),
                                    np.zeros((4, 4, 3), np.float64),
                                    np.zeros((0, 4, 3), np.uint8)])
def test_refuses_what_is_not_an_rgb_image(pixels):
    with pytest.raises(ValueError, match="RGB image"):
        rgb_png(pixels, level=3)
