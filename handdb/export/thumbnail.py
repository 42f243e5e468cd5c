"""A clip's thumbnail: the preview's contact sheet without text, drawn with numpy.

Same panels as :func:`handdb.export.preview.write_preview_png` (the layout of
:mod:`handdb.export.sheet`: one column per frame, the camera's view above a side view,
bones coloured by finger, joints black, filled joints magenta, the truth's bones faint
grey beneath, missing joints leave gaps), but no title, ticks,
labels or legend: the pixels are set in a numpy array and saved with Pillow. That costs
a few milliseconds where matplotlib's text and tick machinery costs a fifth of a second,
which is why the build writes this one for every clip. The sheet has a handful of
colours, so it is painted as indices into :data:`PALETTE` and saved as a palette PNG:
a third of the encoding time of the same pixels in RGB, and a smaller file.
"""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np
from PIL import Image

from handdb.export.sheet import (
    DEFAULT_PREVIEW_FRAMES,
    FILLED_RGB,
    FINGER_RGB,
    TRUTH_RGB,
    VIEWS,
    aligned_truth,
    preview_frames,
    view_box,
)
from handdb.hand.skeletons import Skeleton

#: Side of a square panel, and the gap between panels and around the sheet, pixels.
PANEL_PIXELS = 160
GAP_PIXELS = 6
#: Bone and joint thickness, pixels.
BONE_PIXELS = 2
JOINT_PIXELS = 3
#: Side of a filled joint's square, pixels: larger than an observed joint's.
FILLED_PIXELS = 5
_BORDER = (160, 160, 160)
_JOINT = (0, 0, 0)

#: The thumbnail's colours: the background, the panels' borders, joints, filled joints,
#: the truth's bones, then each finger's bones (in :data:`FINGER_RGB`'s order).
PALETTE = np.array([(255, 255, 255), _BORDER, _JOINT, FILLED_RGB, TRUTH_RGB,
                    *FINGER_RGB.values()], dtype=np.uint8)
_BORDER_INK, _JOINT_INK, _FILLED_INK, _TRUTH_INK = 1, 2, 3, 4
_FINGER_INK = {finger: 5 + i for i, finger in enumerate(FINGER_RGB)}

#: zlib strategy of the PNG: run-length matches only. A palette sheet is long runs of
#: background and few inks: encoding takes half the time of zlib's default strategy
#: (1.0 against 2.1 ms) and the file is 8 % smaller, same pixels.
PNG_STRATEGY = zlib.Z_RLE


def _paint(image: np.ndarray, points: np.ndarray, colours: np.ndarray, size: int) -> None:
    """Paint a ``size`` x ``size`` square of ``colours`` ``(n,)`` at ``points`` ``(n, 2)``.

    ``points`` are ``(column, row)`` pixel coordinates; squares are clipped to the image.
    Where squares overlap, the later point's colour wins.
    """
    corner = np.rint(points).astype(np.intp) - (size - 1) // 2
    height, width = image.shape[:2]
    for d_row in range(size):
        for d_column in range(size):
            column, row = corner[:, 0] + d_column, corner[:, 1] + d_row
            inside = (column >= 0) & (column < width) & (row >= 0) & (row < height)
            image[row[inside], column[inside]] = colours[inside]


def _segment_points(starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points one pixel apart along segments ``(n, 2)``, and the segment of each point.

    Returns ``(m, 2)`` pixel coordinates and ``(m,) int`` segment indices, segments in order.
    """
    steps = np.ceil(np.abs(ends - starts).max(axis=1)).astype(np.intp) + 1   # (n,) >= 1
    segment = np.repeat(np.arange(len(starts)), steps)
    first = np.repeat(np.cumsum(steps) - steps, steps)
    fraction = (np.arange(len(segment)) - first) / np.maximum(steps[segment] - 1, 1)
    return starts[segment] + fraction[:, None] * (ends - starts)[segment], segment


def _paint_bones(image: np.ndarray, pixels: np.ndarray, bones: np.ndarray,
                 bone_ink: np.ndarray) -> None:
    """Paint the bones ``(B, 2)`` of poses at ``pixels`` ``(k, J, 2)``, ``bone_ink`` ``(B,)``."""
    ends = pixels[:, bones]                                                 # (k, B, 2, 2)
    drawn = np.isfinite(ends).all(axis=(-2, -1))                            # (k, B)
    points, segment = _segment_points(ends[drawn][:, 0], ends[drawn][:, 1])
    colours = np.broadcast_to(bone_ink, drawn.shape)[drawn]
    _paint(image, points, colours[segment], BONE_PIXELS)


def _paint_joints(image: np.ndarray, joints: np.ndarray, ink: int, size: int) -> None:
    """Paint squares of palette index ``ink`` at the finite rows of ``joints`` ``(n, 2)``."""
    placed = joints[np.isfinite(joints).all(axis=1)]
    _paint(image, placed, np.full(len(placed), ink, np.uint8), size)


def thumbnail_image(
    skeleton: Skeleton, xyz: np.ndarray, count: int = DEFAULT_PREVIEW_FRAMES, *,
    filled: np.ndarray | None = None, truth: np.ndarray | None = None,
) -> np.ndarray:
    """Draw the contact sheet of ``count`` frames of ``xyz`` as an RGB image.

    :data:`PALETTE`'s colours of :func:`thumbnail_inks`, which takes the same arguments
    and says what they are; returns ``(H, W, 3) uint8``.
    """
    return PALETTE[thumbnail_inks(skeleton, xyz, count, filled=filled, truth=truth)]


def thumbnail_inks(
    skeleton: Skeleton, xyz: np.ndarray, count: int = DEFAULT_PREVIEW_FRAMES, *,
    filled: np.ndarray | None = None, truth: np.ndarray | None = None,
) -> np.ndarray:
    """Draw the contact sheet of ``count`` frames of ``xyz`` in :data:`PALETTE`'s colours.

    Parameters
    ----------
    skeleton
        Skeleton of ``xyz``.
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, handdb's camera frame; NaN
        where a joint has no position. ``T > 0``.
    count
        Frames to show.
    filled
        ``(T, J) bool``: the joints that were missing and gap-filled, drawn in
        :data:`~handdb.export.sheet.FILLED_RGB`; ``None``: none.
    truth
        Ground truth ``(T, J, 3) float64``, clip units, or ``None``; its bones are drawn
        faintly beneath, root on the clip's root (:func:`~handdb.export.sheet.aligned_truth`).

    Returns
    -------
    numpy.ndarray
        ``(H, W) uint8`` indices into :data:`PALETTE`: ``len(VIEWS)`` rows and
        ``min(count, T)`` columns of square panels of :data:`PANEL_PIXELS`,
        :data:`GAP_PIXELS` apart.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    frames = preview_frames(len(xyz), count)
    centre, half = view_box(xyz)
    pitch = PANEL_PIXELS + GAP_PIXELS
    image = np.zeros((GAP_PIXELS + len(VIEWS) * pitch, GAP_PIXELS + len(frames) * pitch),
                     dtype=np.uint8)
    poses = xyz[frames]                                                     # (k, J, 3)
    truths = (None if truth is None else
              aligned_truth(np.asarray(truth, np.float64)[frames], poses, skeleton.root))
    marked = (np.zeros(poses.shape[:2], bool) if filled is None
              else np.asarray(filled, bool)[frames])                        # (k, J)
    to_pixels = PANEL_PIXELS / (2 * half)
    left = GAP_PIXELS + pitch * np.arange(len(frames))                      # (k,)
    bone_ink = np.array([_FINGER_INK[skeleton.fingers[child]] for child in skeleton.bones[:, 1]],
                        dtype=np.uint8)                                     # (B,)
    truth_ink = np.full(bone_ink.shape, _TRUTH_INK, np.uint8)

    def to_panel(points: np.ndarray, axis: int, top: int) -> np.ndarray:
        """Pixel ``(column, row)`` of ``points`` ``(k, J, 3)`` in the row at ``top``."""
        across = (points[..., axis] - (centre[axis] - half)) * to_pixels + left[:, None]
        down = (points[..., 1] - (centre[1] - half)) * to_pixels + top
        return np.stack([across, down], axis=-1)                            # (k, J, 2)

    for row, (_, axis, _) in enumerate(VIEWS):
        top = GAP_PIXELS + row * pitch
        for x in left:
            image[top - 1:top + PANEL_PIXELS + 1, [x - 1, x + PANEL_PIXELS]] = _BORDER_INK
            image[[top - 1, top + PANEL_PIXELS], x - 1:x + PANEL_PIXELS + 1] = _BORDER_INK
        if truths is not None:
            _paint_bones(image, to_panel(truths, axis, top), skeleton.bones, truth_ink)
        pixels = to_panel(poses, axis, top)
        _paint_bones(image, pixels, skeleton.bones, bone_ink)
        _paint_joints(image, pixels[~marked], _JOINT_INK, JOINT_PIXELS)
        _paint_joints(image, pixels[marked], _FILLED_INK, FILLED_PIXELS)
    return image


def write_thumbnail_png(
    path: str | Path, *, skeleton: Skeleton, xyz: np.ndarray,
    count: int = DEFAULT_PREVIEW_FRAMES, filled: np.ndarray | None = None,
    truth: np.ndarray | None = None,
) -> Path:
    """Draw :func:`thumbnail_inks` of ``xyz`` and save it as a palette PNG at ``path``.

    Parameters
    ----------
    path
        Output ``.png`` file; its folder must exist.
    skeleton, xyz, count, filled, truth
        As for :func:`thumbnail_image`.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    picture = Image.fromarray(thumbnail_inks(skeleton, xyz, count, filled=filled, truth=truth))
    picture.putpalette(PALETTE.tobytes())
    picture.save(path, format="PNG", compress_type=PNG_STRATEGY)
    return path
