"""A clip's preview: a PNG contact sheet of a few frames of its skeleton (matplotlib).

The sheet's layout is :mod:`handdb.export.sheet`'s. Bones are coloured by finger; missing
joints leave gaps. Every panel shares one scale, so only the first panel of a row carries
ticks; frames are labelled with their time and the figure with a title and a legend. The
build draws the text-free :mod:`handdb.export.thumbnail` instead (a tenth of the cost);
``handdb preview`` draws this sheet of a stored clip on demand.

Drawing is kept cheap all the same: each row is a single Axes whose panels sit side by
side in data coordinates (an Axes costs more to make and draw than everything in it), a
row's bones are one :class:`~matplotlib.collections.LineCollection`, and the layout is
fixed in inches. The
figure is drawn with the Agg canvas directly (no pyplot state), so previews can be made
from worker threads.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator

from handdb.export.sheet import (
    DEFAULT_PREVIEW_FRAMES,
    FILLED_COLOUR,
    FINGER_COLOURS,
    TRUTH_COLOUR,
    VIEWS,
    aligned_truth,
    preview_frames,
    view_box,
)
from handdb.hand.skeletons import FINGERS, Skeleton

_DPI = 100
#: Fixed layout, inches: side of a square panel, gaps between panels, figure margins.
_PANEL = 2.0
_COLUMN_GAP = 0.15
_ROW_GAP = 0.5
_LEFT, _RIGHT, _TOP, _BOTTOM = 0.75, 0.1, 0.55, 0.45
_TICKS_PER_AXIS = 4


def _sheet(n_columns: int) -> tuple[Figure, list[Axes]]:
    """A figure with one Axes per view, each as wide as ``n_columns`` square panels."""
    n_rows = len(VIEWS)
    row_width = n_columns * _PANEL + (n_columns - 1) * _COLUMN_GAP
    width = _LEFT + row_width + _RIGHT
    height = _TOP + n_rows * _PANEL + (n_rows - 1) * _ROW_GAP + _BOTTOM
    figure = Figure(figsize=(width, height), dpi=_DPI)
    FigureCanvasAgg(figure)
    rows = [figure.add_axes((_LEFT / width,
                             (_BOTTOM + (n_rows - 1 - row) * (_PANEL + _ROW_GAP)) / height,
                             row_width / width, _PANEL / height))
            for row in range(n_rows)]
    return figure, rows


def _scale_ticks(low: float, high: float) -> np.ndarray:
    """Round tick values inside ``[low, high]``, ``(n,) float64``."""
    values = np.asarray(MaxNLocator(_TICKS_PER_AXIS).tick_values(low, high))
    return values[(values >= low) & (values <= high)]


def write_preview_png(
    path: str | Path,
    *,
    skeleton: Skeleton,
    xyz: np.ndarray,
    units: str,
    title: str = "",
    fps: float | None = None,
    count: int = DEFAULT_PREVIEW_FRAMES,
    filled: np.ndarray | None = None,
    truth: np.ndarray | None = None,
) -> Path:
    """Draw a contact sheet of ``count`` frames of ``xyz`` and save it as PNG.

    Parameters
    ----------
    path
        Output ``.png`` file; its folder must exist.
    skeleton
        Skeleton of ``xyz``.
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, handdb's camera frame; NaN
        where a joint has no position.
    units
        Length unit of ``xyz``, for the axis labels.
    title
        Figure title, e.g. the clip id.
    fps
        Frames per second; when given, panels show the time of their frame.
    count
        Frames to show.
    filled
        ``(T, J) bool``: the joints that were missing and gap-filled, drawn as magenta
        rings (:data:`~handdb.export.sheet.FILLED_COLOUR`); ``None``: none.
    truth
        Ground truth ``(T, J, 3) float64``, clip units, or ``None``; its bones are drawn
        faintly beneath, root on the clip's root (:func:`~handdb.export.sheet.aligned_truth`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    xyz = np.asarray(xyz, dtype=np.float64)
    frames = preview_frames(len(xyz), count)
    centre, half = view_box(xyz)
    side = 2 * half
    pitch = side * (1 + _COLUMN_GAP / _PANEL)             # panel to panel, clip units
    panel_left = np.arange(len(frames)) * pitch           # (k,) left edge of each panel
    poses = xyz[frames]                                   # (k, J, 3)
    drawn = np.isfinite(poses[:, skeleton.bones]).all(axis=(-2, -1))  # (k, B)
    bone_colours = np.array([FINGER_COLOURS[skeleton.fingers[c]] for c in skeleton.bones[:, 1]])
    colours = np.broadcast_to(bone_colours, drawn.shape)[drawn]
    truths = (None if truth is None else
              aligned_truth(np.asarray(truth, np.float64)[frames], poses, skeleton.root))
    marked = (np.zeros(poses.shape[:2], bool) if filled is None
              else np.asarray(filled, bool)[frames])                       # (k, J)

    figure, rows = _sheet(len(frames))
    for ax, (label, axis, view) in zip(rows, VIEWS, strict=True):
        across = poses[..., axis] - (centre[axis] - half) + panel_left[:, None]  # (k, J)
        down = poses[..., 1]
        if truths is not None:
            t_across = truths[..., axis] - (centre[axis] - half) + panel_left[:, None]
            t_segments = np.stack([t_across[:, skeleton.bones], truths[..., 1][:, skeleton.bones]],
                                  axis=-1)                                # (k, B, 2, 2)
            shown = np.isfinite(t_segments).all(axis=(-2, -1))
            ax.add_collection(LineCollection(t_segments[shown], colors=TRUTH_COLOUR,
                                             linewidths=2, zorder=1))
        segments = np.stack([across[:, skeleton.bones], down[:, skeleton.bones]], axis=-1)
        ax.add_collection(LineCollection(segments[drawn], colors=colours, linewidths=2,
                                         zorder=2))
        ax.plot(across[~marked], down[~marked], ".", color="black", ms=4, zorder=3)
        ax.plot(across[marked], down[marked], "o", mfc="none", mec=FILLED_COLOUR, mew=1.2,
                ms=5, zorder=3)
        ax.add_collection(PatchCollection(
            [Rectangle((left, centre[1] - half), side, side) for left in panel_left],
            facecolor="none", edgecolor="black", linewidth=0.8, clip_on=False))
        ax.set_xlim(0, panel_left[-1] + side)
        ax.set_ylim(centre[1] + half, centre[1] - half)
        ax.set_aspect("equal")
        ax.set_frame_on(False)
        scale = _scale_ticks(centre[axis] - half, centre[axis] + half)
        ax.set_xticks(scale - (centre[axis] - half), [f"{v:g}" for v in scale])
        ax.set_yticks(_scale_ticks(centre[1] - half, centre[1] + half))
        ax.tick_params(labelsize=6, length=2, pad=1)
        ax.set_xlabel(f"{label} ({units})", fontsize=7, labelpad=1, ha="center",
                      x=half / (panel_left[-1] + side))
        ax.set_ylabel(f"{view}\ny ({units}, down)", fontsize=7, labelpad=1)
    for left, frame in zip(panel_left, frames, strict=True):
        when = f" · {frame / fps:.2f} s" if fps else ""
        rows[0].text(left + half, 1.02, f"frame {frame}{when}", fontsize=8, ha="center",
                     va="bottom", transform=rows[0].get_xaxis_transform())
    handles = [Line2D([], [], color=FINGER_COLOURS[f], lw=2, label=f) for f in FINGERS]
    if marked.any():
        handles.append(Line2D([], [], ls="none", marker="o", mfc="none", mec=FILLED_COLOUR,
                              label="filled"))
    if truths is not None:
        handles.append(Line2D([], [], color=TRUTH_COLOUR, lw=2, label="truth"))
    figure.legend(handles=handles, loc="lower center", ncols=len(handles), fontsize=7,
                  frameon=False, borderaxespad=0.2)
    if title:
        figure.suptitle(title, fontsize=10)
    figure.savefig(path, format="png")
    return path
