"""A clip's depth comparison chart: mean ``|ΔZ|`` per joint and method, drawn with Pillow.

The build draws one for every clip with ground truth (``reports/<clip>/depth.png``), so it
is drawn the way the thumbnail is (:mod:`handdb.export.thumbnail`): rectangles and a few
lines of text straight onto the image, a few milliseconds where matplotlib's axes, ticks
and text layout cost a quarter of a second per clip. Same content as before: a title, one
group of bars per joint (in skeleton order, names slanted beneath), one colour per method
with a legend, a labelled value axis with round ticks and light grid lines.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from handdb.validation.png import rgb_png

#: Size of the chart, pixels (width, height).
CHART_PIXELS = (1200, 400)
#: Space around the plot, pixels: left (value labels), right, top (title), bottom (joints).
_LEFT, _RIGHT, _TOP, _BOTTOM = 72, 12, 32, 100
#: Text height, pixels.
_FONT_PIXELS = 12
_TITLE_PIXELS = 14
#: Slant of the joint names, degrees counter-clockwise.
_NAME_DEGREES = 60
#: zlib level of the chart's PNG (:func:`handdb.validation.png.rgb_png`): on its flat
#: colours level 3 finds nearly all that the default 6 does in about half the time.
PNG_COMPRESS_LEVEL = 3
#: Slanted joint names kept for later charts: every joint name of a few skeletons.
_LABEL_CACHE = 256
#: Share of a joint's slot the bars of all methods fill.
_GROUP_WIDTH = 0.8
#: Ticks on the value axis, about.
_TICKS = 5
#: Method colours, in order (matplotlib's default cycle, as the chart had before).
METHOD_RGB = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
              (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207))
_INK, _GRID, _PAPER = (0, 0, 0), (225, 225, 225), (255, 255, 255)

#: What Pillow's ``load_default`` gives: a scalable font, or its bitmap font without FreeType.
Font = ImageFont.FreeTypeFont | ImageFont.ImageFont


def nice_step(top: float, ticks: int = _TICKS) -> float:
    """A tick step of 1, 2 or 5 times a power of ten giving about ``ticks`` ticks to ``top``."""
    if not top > 0 or not math.isfinite(top):
        return 1.0
    raw = top / ticks
    power = 10.0 ** math.floor(math.log10(raw))
    return next(m * power for m in (1.0, 2.0, 5.0, 10.0) if m * power >= raw)


@functools.lru_cache(maxsize=_LABEL_CACHE)
def _slanted(text: str) -> tuple[Image.Image, Image.Image]:
    """``text`` turned :data:`_NAME_DEGREES` counter-clockwise: its ink and its opacity.

    The ink (``RGB``) and opacity (``L``) images are what :meth:`PIL.Image.Image.paste`
    takes; they are shared between charts, so they are read, never drawn on. A skeleton's
    joint names are the same in every chart, and rotating them costs as much as drawing
    the rest of the chart.
    """
    font = ImageFont.load_default(_FONT_PIXELS)
    left, top, right, bottom = (int(round(edge)) for edge in font.getbbox(text))
    label = Image.new("LA", (right - left + 2, bottom - top + 2), (0, 0))
    ImageDraw.Draw(label).text((1 - left, 1 - top), text, font=font, fill=(0, 255))
    label = label.rotate(_NAME_DEGREES, expand=True, resample=Image.Resampling.BICUBIC)
    return label.convert("RGB"), label.getchannel("A")


def draw_comparison_chart(title: str, joints: tuple[str, ...], methods: list[str],
                          heights: np.ndarray, axis_label: str) -> bytes:
    """Draw grouped bars as a PNG.

    Parameters
    ----------
    title
        Above the plot.
    joints
        One group of bars each, left to right.
    methods
        One bar per group each, and a legend entry.
    heights
        ``(M, J)`` float64, the bars' values in the units of ``axis_label``; NaN draws none.
    axis_label
        Beside the value axis.

    Returns
    -------
    bytes
        The PNG file's content.
    """
    width, height = CHART_PIXELS
    image = Image.new("RGB", CHART_PIXELS, _PAPER)
    draw = ImageDraw.Draw(image)
    font, title_font = ImageFont.load_default(_FONT_PIXELS), ImageFont.load_default(_TITLE_PIXELS)
    left, right, top, bottom = _LEFT, width - _RIGHT, _TOP, height - _BOTTOM
    finite = heights[np.isfinite(heights)]
    step = nice_step(float(finite.max()) if finite.size else 0.0)
    y_top = step * max(1, math.ceil(float(finite.max()) / step)) if finite.size else step

    def row(value: float) -> float:
        return bottom - (bottom - top) * value / y_top

    for k in range(int(round(y_top / step)) + 1):
        y = row(k * step)
        draw.line([(left, y), (right, y)], fill=_GRID)
        draw.line([(left - 4, y), (left, y)], fill=_INK)
        draw.text((left - 6, y), f"{k * step:g}", font=font, fill=_INK, anchor="rm")
    slot = (right - left) / max(len(joints), 1)
    bar = slot * _GROUP_WIDTH / max(len(methods), 1)
    for m, method_heights in enumerate(heights):
        colour = METHOD_RGB[m % len(METHOD_RGB)]
        for j, value in enumerate(method_heights):
            if np.isfinite(value) and value > 0:
                x = left + slot * (j + (1 - _GROUP_WIDTH) / 2) + m * bar
                draw.rectangle([(x, row(float(value))), (x + bar - 1, bottom)], fill=colour)
    for j, joint in enumerate(joints):
        centre = left + slot * (j + 0.5)
        draw.line([(centre, bottom), (centre, bottom + 4)], fill=_INK)
        ink, opacity = _slanted(joint)
        image.paste(ink, (int(centre - ink.width), bottom + 6), opacity)
    draw.rectangle([(left, top), (right, bottom)], outline=_INK)
    draw.text(((left + right) / 2, top / 2), title, font=title_font, fill=_INK, anchor="mm")
    _legend(draw, font, methods, right, top)
    axis = Image.new("LA", (int(font.getlength(axis_label)) + 2, _FONT_PIXELS + 4), (0, 0))
    ImageDraw.Draw(axis).text((1, 1), axis_label, font=font, fill=(0, 255))
    axis = axis.rotate(90, expand=True)
    image.paste(axis.convert("RGB"), (4, int((top + bottom - axis.height) / 2)),
                axis.getchannel("A"))
    return rgb_png(np.asarray(image), PNG_COMPRESS_LEVEL)


def _legend(draw: ImageDraw.ImageDraw, font: Font, methods: list[str],
            right: float, top: float) -> None:
    """A box of the methods' colours and names in the plot's top right corner."""
    line = _FONT_PIXELS + 6
    text_width = max((font.getlength(m) for m in methods), default=0.0)
    box_left, box_top = right - text_width - 40, top + 8
    draw.rectangle([(box_left, box_top), (right - 8, box_top + line * len(methods) + 6)],
                   fill=_PAPER, outline=_GRID)
    for m, method in enumerate(methods):
        y = box_top + 4 + line * m
        draw.rectangle([(box_left + 6, y + 2), (box_left + 22, y + line - 6)],
                       fill=METHOD_RGB[m % len(METHOD_RGB)])
        draw.text((box_left + 28, y + (line - 4) / 2), method, font=font, fill=_INK,
                  anchor="lm")
