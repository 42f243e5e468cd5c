"""Validation of lifted clips against ground truth (the thesis's Table 4.1, and more).

Depth is compared root-relative: for truth and estimate alike, every joint's ``z`` minus
the root's ``z`` in the same frame, so the unknown distance of the hand from the camera
drops out. Nothing is fitted to the truth: an orthographic estimate keeps the scale its
method derived from the bone lengths (``x = u / s``), which is already in clip units.
The position error (MPJPE) compares root-relative ``(x, y, z)`` the same way.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pyarrow as pa

from handdb.clip import METERS_PER_UNIT
from handdb.hand.skeletons import Skeleton
from handdb.lifting.result import LiftResult
from handdb.store import tables
from handdb.validation.chart import draw_comparison_chart
from handdb.vectors import norm

#: Bones whose true depth span is below this are left out of the sign accuracy, metres.
SIGN_THRESHOLD_M = 0.005



def _xyz(estimate: LiftResult | np.ndarray) -> np.ndarray:
    return estimate.xyz if isinstance(estimate, LiftResult) else np.asarray(estimate)


def joint_errors(truth: np.ndarray, estimate: np.ndarray, skeleton: Skeleton,
                 sign_threshold: float) -> dict[str, np.ndarray]:
    """Per-joint error statistics of one estimate.

    Parameters
    ----------
    truth, estimate
        ``(T, J, 3) float64``, clip units, camera frame; NaN where absent.
    skeleton
        Gives the root and each joint's parent.
    sign_threshold
        Clip units: bones with a smaller true ``|dZ|`` are not counted for sign accuracy.

    Returns
    -------
    dict
        ``(J,)`` arrays: ``n`` (frames with both values), ``dz_min``, ``dz_max``,
        ``dz_mean``, ``dz_std`` (of ``|ΔZ|`` root-relative, population std), ``sign_accuracy``
        and ``n_sign`` (bone ending at the joint; NaN / 0 at the root), ``mpjpe``.
    """
    root = skeleton.root
    true_rel = truth - truth[:, root : root + 1]
    est_rel = estimate - estimate[:, root : root + 1]
    dz = np.abs(est_rel[..., 2] - true_rel[..., 2])
    valid = np.isfinite(dz)
    n = valid.sum(axis=0)
    masked = np.where(valid, dz, np.nan)
    position = norm(est_rel - true_rel)

    parents = np.where(skeleton.parents < 0, root, skeleton.parents)
    true_bone = truth[..., 2] - truth[:, parents, 2]
    est_bone = estimate[..., 2] - estimate[:, parents, 2]
    counted = (np.abs(true_bone) >= sign_threshold) & np.isfinite(est_bone)
    counted[:, root] = False
    agree = (np.sign(true_bone) == np.sign(est_bone)) & counted
    n_sign = counted.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        sign_accuracy = np.where(n_sign > 0, agree.sum(axis=0) / n_sign, np.nan)
    dz_min, dz_max, dz_mean, dz_std = _column_statistics(masked)
    return {
        "n": n,
        "dz_min": dz_min,
        "dz_max": dz_max,
        "dz_mean": dz_mean,
        "dz_std": dz_std,
        "sign_accuracy": sign_accuracy,
        "n_sign": n_sign,
        "mpjpe": _column_statistics(position, spread=False)[2],
    }


def _column_statistics(values: np.ndarray, *, spread: bool = True) -> tuple[np.ndarray, ...]:
    """NaN-aware minimum, maximum, mean and population std over axis 0 of ``(T, J)`` values.

    Each ``(J,)``, NaN for a column without a finite value. The figures of ``numpy.nanmin``,
    ``nanmax``, ``nanmean`` and ``nanstd`` on the columns with one, bit for bit: the same
    numpy operations on the same array, its NaN replaced and its columns counted and
    summed once for the four instead of once each. ``spread=False`` leaves out the minimum,
    maximum and std (NaN).
    """
    statistics = np.full((4, values.shape[1]), np.nan)
    some = np.isfinite(values).any(axis=0)
    columns = values[:, some]
    missing = np.isnan(columns)
    filled = np.where(missing, 0.0, columns)
    count = np.sum(~missing, axis=0, dtype=np.intp)
    mean = np.sum(filled, axis=0) / count
    statistics[2, some] = mean
    if spread:
        statistics[0, some] = np.fmin.reduce(columns, axis=0)
        statistics[1, some] = np.fmax.reduce(columns, axis=0)
        deviation = filled - mean
        deviation[missing] = 0.0
        statistics[3, some] = np.sqrt(np.sum(deviation * deviation, axis=0) / count)
    return tuple(statistics)


def validation_table(clip_id: str, truth: np.ndarray,
                     estimates: Mapping[str, LiftResult | np.ndarray], skeleton: Skeleton,
                     units: str) -> pa.Table:
    """Rows of ``validation_joint``: one per method and joint.

    Parameters
    ----------
    clip_id
        The clip.
    truth
        ``(T, J, 3) float64``, ``units``, camera frame.
    estimates
        Method name -> its :class:`LiftResult` (or ``(T, J, 3)`` positions).
    skeleton
        Orders the joint axis of ``truth`` and the estimates.
    units
        Length unit of the clip (a key of :data:`handdb.clip.METERS_PER_UNIT`).

    Returns
    -------
    pyarrow.Table
        Conforming to ``schemas/tables/validation_joint.json``.
    """
    threshold = SIGN_THRESHOLD_M / METERS_PER_UNIT[units]
    columns: dict[str, list] = {key: [] for key in (
        "method", "joint", "n", "dz_min", "dz_max", "dz_mean", "dz_std", "sign_accuracy",
        "n_sign", "mpjpe")}
    for method, estimate in estimates.items():
        stats = joint_errors(truth, _xyz(estimate), skeleton, threshold)
        columns["method"] += [method] * skeleton.n_joints
        columns["joint"] += list(skeleton.joints)
        for key, values in stats.items():
            columns[key] += list(values)
    root = skeleton.joints[skeleton.root]
    columns["n_sign"] = [None if joint == root else int(n)
                         for joint, n in zip(columns["joint"], columns["n_sign"], strict=True)]
    return tables.from_columns("validation_joint", {
        "clip_id": clip_id, **columns, "units": units})


def clip_summary(table: pa.Table) -> dict[str, dict[str, float]]:
    """Whole-clip figures per method from ``validation_joint`` rows.

    Returns
    -------
    dict
        Method -> ``dz_mean`` (mean ``|ΔZ|`` over every joint and frame),
        ``sign_accuracy`` (over every counted bone and frame) and ``mpjpe``.
    """
    rows = table.to_pydict()
    out: dict[str, dict[str, float]] = {}
    methods = np.asarray(rows["method"])
    n = np.asarray(rows["n"], dtype=float)
    n_sign = np.asarray([v or 0 for v in rows["n_sign"]], dtype=float)
    for method in dict.fromkeys(rows["method"]):
        pick = methods == method
        accuracy = np.nan_to_num(np.asarray(rows["sign_accuracy"], dtype=float))
        out[method] = {
            "dz_mean": float(np.sum((np.asarray(rows["dz_mean"], dtype=float) * n)[pick])
                             / np.sum(n[pick])),
            "sign_accuracy": float(np.sum((accuracy * n_sign)[pick]) / np.sum(n_sign[pick])),
            "mpjpe": float(np.sum((np.asarray(rows["mpjpe"], dtype=float) * n)[pick])
                           / np.sum(n[pick])),
        }
    return out


def _number(value: float | None) -> str:
    """Three significant digits, or a dash where a method gave no value."""
    return "-" if value is None or not np.isfinite(value) else f"{value:.3g}"


def markdown_summary(clip_id: str, table: pa.Table) -> str:
    """Compare the methods on one clip in markdown (whole clip, then per joint)."""
    units = table.column("units")[0].as_py() if table.num_rows else ""
    summary = clip_summary(table)
    lines = [f"## Depth validation: {clip_id}", "",
             f"| method | mean abs dZ ({units}) | sign accuracy | MPJPE ({units}) |",
             "|---|---:|---:|---:|"]
    for method, figures in sorted(summary.items(), key=lambda kv: kv[1]["dz_mean"]):
        lines.append(f"| {method} | {_number(figures['dz_mean'])} | "
                     f"{figures['sign_accuracy']:.1%} | {_number(figures['mpjpe'])} |")
    rows = table.to_pylist()
    methods = list(summary)
    lines += ["", "Mean abs dZ per joint (Table 4.1's average column):", "",
              "| joint | " + " | ".join(methods) + " |",
              "|---|" + "---:|" * len(methods)]
    by_joint: dict[str, dict[str, float]] = {}
    for row in rows:
        by_joint.setdefault(row["joint"], {})[row["method"]] = row["dz_mean"]
    for joint, values in by_joint.items():
        cells = " | ".join(_number(values.get(m)) for m in methods)
        lines.append(f"| {joint} | {cells} |")
    return "\n".join(lines) + "\n"


def comparison_chart(clip_id: str, table: pa.Table, skeleton: Skeleton) -> bytes:
    """Draw a PNG bar chart of mean ``|ΔZ|`` per joint and method for one clip.

    Drawn with Pillow (:func:`handdb.validation.chart.draw_comparison_chart`), so charts
    can be made from worker threads at once.

    Parameters
    ----------
    clip_id
        The clip, for the title.
    table
        Its ``validation_joint`` rows (see :func:`validation_table`).
    skeleton
        Orders the joints along the x axis.

    Returns
    -------
    bytes
        The PNG file's content.
    """
    rows = table.to_pylist()
    methods = list(dict.fromkeys(r["method"] for r in rows))
    values = {(r["method"], r["joint"]): r["dz_mean"] for r in rows}
    heights = np.array([[np.nan if values.get((m, joint)) is None else values[(m, joint)]
                         for joint in skeleton.joints] for m in methods],
                       dtype=np.float64).reshape(len(methods), skeleton.n_joints)
    units = rows[0]["units"] if rows else ""
    return draw_comparison_chart(f"{clip_id}: depth error per joint", skeleton.joints,
                                 methods, heights, f"mean |ΔZ| root-relative ({units})")
