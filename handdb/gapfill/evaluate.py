"""Score gap-filling methods: hide known points under masks, fill, compare with the truth.

Masks (see :mod:`handdb.gapfill.masks` and :mod:`handdb.gapfill.occlusion`):

* ``thesis-table-4.2``: the thesis's Table 4.2 pattern; the clip is cut into 100-frame
  clips (a shorter clip is one clip with the pattern cut short), each filled on its own.
* ``random-gaps``: :data:`~handdb.gapfill.masks.RANDOM_GAPS` random interior gaps of 1-60
  frames per 400 frames, seeded.
* ``occlusion``: the points the hand's own mesh hides from the camera (needs 3D joints).

:func:`evaluate_clip` returns the ``gapfill_eval`` rows (one per mask, method and joint,
errors in pixels) and the per-point errors; :func:`plot_errors` draws them like the
thesis's Figure 4.6 (:func:`plot_masks`, every mask of a clip in one chart);
:func:`pooled_rmse` and :func:`rmse_markdown` summarise rows of many clips.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np
import pyarrow as pa
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from handdb.errors import ClipDataError, UnknownNameError
from handdb.gapfill.masks import (
    RANDOM_GAPS,
    THESIS_CLIP_FRAMES,
    random_gaps_mask,
    thesis_table_4_2_mask,
)
from handdb.gapfill.methods import METHODS
from handdb.gapfill.registry import fill_gaps
from handdb.hand.skeletons import Skeleton
from handdb.store import tables

#: Mask names.
THESIS_MASK = "thesis-table-4.2"
RANDOM_MASK = "random-gaps"
OCCLUSION_MASK = "occlusion"
MASKS = (THESIS_MASK, RANDOM_MASK, OCCLUSION_MASK)

#: Frames per :data:`~handdb.gapfill.masks.RANDOM_GAPS` random gaps.
RANDOM_GAPS_PER_FRAMES = 400

#: Held while a chart is drawn: matplotlib's text layout is not thread-safe, and the
#: evaluation flow scores clips in threads.
_DRAWING = threading.Lock()


@dataclass(frozen=True)
class Evaluation:
    """Scores of every method under every mask on one clip.

    Attributes
    ----------
    table
        ``gapfill_eval`` rows.
    errors
        ``(mask, method) -> (T, J) float64``: the error of each hidden point, pixels (NaN
        where not hidden or not filled).
    hidden
        ``mask -> (T, J) bool``: the hidden points.
    """

    table: pa.Table
    errors: dict[tuple[str, str], np.ndarray]
    hidden: dict[str, np.ndarray]


def mask_segments(
    mask: str, uv: np.ndarray, skeleton: Skeleton, *, xyz: np.ndarray | None = None,
    seed: int = 0,
) -> list[tuple[slice, np.ndarray]]:
    """Return the frame ranges filled on their own under ``mask``, with their hidden points.

    Parameters
    ----------
    mask
        One of :data:`MASKS`.
    uv
        ``(T, J, 2) float64``, pixels, the full tracks.
    skeleton
        The clip's skeleton.
    xyz
        ``(T, J, 3) float64`` camera-frame joints; needed by ``occlusion``.
    seed
        Seed of ``random-gaps``.

    Returns
    -------
    list of (slice, numpy.ndarray)
        Frame range and ``(frames, J) bool`` hidden points.
    """
    n_frames = uv.shape[0]
    if mask == THESIS_MASK:
        pattern = thesis_table_4_2_mask(skeleton)
        starts = range(0, max(n_frames - THESIS_CLIP_FRAMES + 1, 1), THESIS_CLIP_FRAMES)
        return [(slice(s, s + THESIS_CLIP_FRAMES), pattern[: n_frames - s]) for s in starts]
    if mask == RANDOM_MASK:
        n_gaps = max(1, round(RANDOM_GAPS * n_frames / RANDOM_GAPS_PER_FRAMES))
        return [(slice(0, n_frames), random_gaps_mask(n_frames, skeleton.n_joints,
                                                      n_gaps=n_gaps, seed=seed))]
    if mask == OCCLUSION_MASK:
        if xyz is None:
            raise ClipDataError("the occlusion mask needs the clip's 3D joints (xyz)")
        from handdb.gapfill.occlusion import occlusion_mask

        return [(slice(0, n_frames), occlusion_mask(xyz, skeleton))]
    raise UnknownNameError("gap-filling mask", mask, tuple(MASKS))


def evaluate_clip(
    clip_id: str,
    uv: np.ndarray,
    skeleton: Skeleton,
    *,
    masks: Sequence[str] = (THESIS_MASK, RANDOM_MASK),
    methods: Sequence[str] | None = None,
    xyz: np.ndarray | None = None,
    seed: int = 0,
) -> Evaluation:
    """Hide known points of a complete clip under each mask and score every method.

    Parameters
    ----------
    clip_id
        Names the clip in the table.
    uv
        ``(T, J, 2) float64``, pixels, complete (no NaN).
    skeleton
        The clip's skeleton.
    masks
        Mask names (see :data:`MASKS`).
    methods
        Method names; every registered method when ``None``.
    xyz, seed
        As for :func:`mask_segments`.

    Returns
    -------
    Evaluation
    """
    methods = tuple(METHODS) if methods is None else tuple(methods)
    columns: dict[str, list] = {name: [] for name in tables.schema("gapfill_eval").names}
    errors, hidden_by_mask = {}, {}
    for mask in masks:
        segments = mask_segments(mask, uv, skeleton, xyz=xyz, seed=seed)
        hidden = np.zeros(uv.shape[:2], dtype=bool)
        for frames, segment_hidden in segments:
            hidden[frames] = segment_hidden
        hidden_by_mask[mask] = hidden
        for method in methods:
            error = np.full(uv.shape[:2], np.nan)
            for frames, segment_hidden in segments:
                truth = uv[frames]
                result = fill_gaps(truth, ~segment_hidden, skeleton, method)
                distance = np.linalg.norm(result.uv - truth, axis=-1)
                error[frames] = np.where(segment_hidden, distance, np.nan)
            errors[(mask, method)] = error
            for j in np.flatnonzero(hidden.any(axis=0)):
                joint_errors = error[hidden[:, j], j]
                scored = joint_errors[np.isfinite(joint_errors)]
                columns["clip_id"].append(clip_id)
                columns["mask"].append(mask)
                columns["method"].append(method)
                columns["joint"].append(skeleton.joints[j])
                columns["n_filled"].append(scored.size)
                columns["rmse"].append(float(np.sqrt(np.mean(scored**2))) if scored.size else None)
                columns["max_error"].append(float(scored.max()) if scored.size else None)
    return Evaluation(tables.from_columns("gapfill_eval", columns), errors, hidden_by_mask)


def overall_rmse(evaluation: Evaluation) -> dict[tuple[str, str], float]:
    """RMSE over every hidden point, pixels, per ``(mask, method)``."""
    return {
        key: float(np.sqrt(np.nanmean(error[evaluation.hidden[key[0]]] ** 2)))
        for key, error in evaluation.errors.items()
    }


def pooled_rmse(table: pa.Table) -> dict[tuple[str, str], float]:
    """RMSE over every filled hidden point, pixels, per ``(mask, method)``, from the rows.

    Pools the per-joint rows of ``gapfill_eval`` (of one clip or many) by their
    ``n_filled``; NaN where nothing was filled.
    """
    rows = table.to_pydict()
    squares: dict[tuple[str, str], list[float]] = {}
    for mask, method, n, rmse in zip(rows["mask"], rows["method"], rows["n_filled"],
                                     rows["rmse"], strict=True):
        total = squares.setdefault((mask, method), [0.0, 0.0])
        if n:
            total[0] += n * rmse**2
            total[1] += n
    return {key: float(np.sqrt(s / n)) if n else float("nan") for key, (s, n) in squares.items()}


def rmse_markdown(table: pa.Table) -> str:
    """Tabulate :func:`pooled_rmse` in markdown: a row per method, a column per mask."""
    rmse = pooled_rmse(table)
    masks = list(dict.fromkeys(mask for mask, _ in rmse))
    methods = list(dict.fromkeys(method for _, method in rmse))
    lines = ["| method | family | " + " | ".join(masks) + " |",
             "|---|---|" + "---:|" * len(masks)]
    for method in methods:
        cells = [f"{rmse[(mask, method)]:.2f}" if (mask, method) in rmse else "-"
                 for mask in masks]
        family = METHODS[method].family if method in METHODS else ""
        lines.append(f"| {method} | {family} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _draw_errors(
    axes: Axes, evaluation: Evaluation, mask: str, skeleton: Skeleton,
    methods: Sequence[str], title: str,
) -> None:
    """Draw one mask's per-frame errors of ``methods`` on ``axes`` (see :func:`plot_errors`)."""
    hidden = evaluation.hidden[mask]
    shown = np.flatnonzero(hidden.any(axis=0))
    n_frames = hidden.shape[0]
    x = np.arange(shown.size * n_frames)
    for method in methods:
        error = evaluation.errors[(mask, method)][:, shown].T.ravel()
        axes.plot(x, np.nan_to_num(error), linewidth=0.9, label=method)
    for k in range(1, shown.size):
        axes.axvline(k * n_frames, color="0.85", linewidth=0.6, zorder=0)
    axes.set_xticks((np.arange(shown.size) + 0.5) * n_frames,
                    [skeleton.joints[j] for j in shown], rotation=60, fontsize=7)
    axes.set_yscale("symlog", linthresh=1.0)
    axes.set_ylim(bottom=0.0)
    axes.set_ylabel("error, pixels (log above 1)")
    axes.set_xlabel("frames of each joint with hidden points")
    axes.set_title(title)
    axes.legend(ncol=4, fontsize=7)


def _methods_of(evaluation: Evaluation, mask: str, methods: Sequence[str] | None) -> list[str]:
    return [m for (k, m) in evaluation.errors if k == mask] if methods is None else list(methods)


def plot_errors(
    evaluation: Evaluation, mask: str, skeleton: Skeleton, path: str | Path,
    *, methods: Sequence[str] | None = None, title: str | None = None,
) -> Path:
    """Draw the error of every frame of every hidden joint, one line per method (Figure 4.6).

    The x axis runs over the frames of each joint in turn (joint 0's frames, then joint
    1's, ...), as in the thesis's figure; only joints with hidden points are drawn.

    Returns
    -------
    pathlib.Path
        The PNG written.
    """
    path = Path(path)
    with _DRAWING:
        figure = Figure(figsize=(12, 4.5))
        _draw_errors(figure.subplots(), evaluation, mask, skeleton,
                     _methods_of(evaluation, mask, methods),
                     title or f"gap-filling error per frame, mask {mask}")
        figure.tight_layout()
        figure.savefig(path, dpi=120)
    return path


def plot_masks(
    evaluation: Evaluation, skeleton: Skeleton, target: str | Path | BinaryIO,
    *, methods: Sequence[str] | None = None, title: str | None = None,
) -> None:
    """Draw :func:`plot_errors`'s chart for every mask of ``evaluation``, one panel each.

    ``target`` is a path or a binary file the PNG is written to.
    """
    masks = list(evaluation.hidden)
    with _DRAWING:
        figure = Figure(figsize=(12, 4.5 * len(masks)))
        for axes, mask in zip(np.atleast_1d(figure.subplots(len(masks), 1)), masks,
                              strict=True):
            _draw_errors(axes, evaluation, mask, skeleton,
                         _methods_of(evaluation, mask, methods), f"mask {mask}")
        if title:
            figure.suptitle(title)
        figure.tight_layout()
        figure.savefig(target, dpi=120, format="png")
