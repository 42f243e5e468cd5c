"""A clip's preview: a PNG contact sheet of a few frames of its skeleton (matplotlib).

Each column is one frame, evenly spaced over the clip; the top row is the camera's view
(``x`` right, ``y`` down) and the bottom row a side view (depth ``z`` to the right, ``y``
down). Bones are coloured by finger; missing joints leave gaps. Every panel shares one
scale so motion between frames reads at a glance. The figure is drawn with the Agg
canvas directly (no pyplot state), so previews can be made from worker threads.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from handdb.skeletons import FINGERS, Skeleton

#: Frames shown by default.
DEFAULT_PREVIEW_FRAMES = 6

#: Colour of each finger's bones (and of the palm's).
FINGER_COLOURS: dict[str, str] = {
    "thumb": "tab:red", "index": "tab:orange", "middle": "tab:green",
    "ring": "tab:blue", "little": "tab:purple", "palm": "0.35",
}

_PANEL_INCHES = 2.2
_DPI = 100
_VIEWS = (("x", 0, "camera view"), ("z", 2, "side view"))


def preview_frames(n_frames: int, count: int = DEFAULT_PREVIEW_FRAMES) -> np.ndarray:
    """Return ``count`` frame indices evenly spaced from first to last, ``(k,) int``."""
    return np.unique(np.linspace(0, n_frames - 1, min(count, n_frames)).round().astype(int))


def write_preview_png(
    path: str | Path,
    *,
    skeleton: Skeleton,
    xyz: np.ndarray,
    units: str,
    title: str = "",
    fps: float | None = None,
    count: int = DEFAULT_PREVIEW_FRAMES,
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

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    xyz = np.asarray(xyz, dtype=np.float64)
    frames = preview_frames(len(xyz), count)
    parents, children = skeleton.bones.T
    bone_colours = [FINGER_COLOURS[skeleton.fingers[c]] for c in children]
    finite = xyz[np.isfinite(xyz).all(axis=-1)]
    centre = (finite.min(axis=0) + finite.max(axis=0)) / 2 if len(finite) else np.zeros(3)
    half = 0.55 * max(float(np.ptp(finite, axis=0).max()) if len(finite) else 1.0, 1e-9)

    figure = Figure(figsize=(_PANEL_INCHES * len(frames), _PANEL_INCHES * len(_VIEWS) + 0.6),
                    dpi=_DPI, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(len(_VIEWS), len(frames), squeeze=False, sharex="row", sharey=True)
    for column, frame in enumerate(frames):
        pose = xyz[frame]
        for row, (label, axis, view) in enumerate(_VIEWS):
            ax = axes[row, column]
            for parent, child, colour in zip(parents, children, bone_colours, strict=True):
                ax.plot(pose[[parent, child], axis], pose[[parent, child], 1], color=colour, lw=2)
            ax.scatter(pose[:, axis], pose[:, 1], s=6, color="black", zorder=3)
            ax.set_xlim(centre[axis] - half, centre[axis] + half)
            ax.set_ylim(centre[1] + half, centre[1] - half)
            ax.set_aspect("equal")
            ax.tick_params(labelsize=6)
            if column == 0:
                ax.set_ylabel(f"{view}\ny ({units}, down)", fontsize=7)
            ax.set_xlabel(f"{label} ({units})", fontsize=7)
            if row == 0:
                when = f" · {frame / fps:.2f} s" if fps else ""
                ax.set_title(f"frame {frame}{when}", fontsize=8)
    handles = [axes[0, 0].plot([], [], color=FINGER_COLOURS[f], label=f)[0] for f in FINGERS]
    figure.legend(handles=handles, loc="outside lower center", ncols=len(FINGERS), fontsize=7)
    if title:
        figure.suptitle(title, fontsize=10)
    figure.savefig(path, format="png")
    return path
