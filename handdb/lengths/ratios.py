"""Relative phalanx lengths from X-ray measurements (Chaudhry, You, Jin & Zhang).

The relative value of a segment is its length over the total length of its finger,
``J = J1 + J2 + J3`` (thumb ``J1 + J2``), computed per image (the paper's eqs. 1-4). Over
the images of a cohort each (finger, segment) gets the paper's mean, minimum, maximum and
range (eqs. 5-10), and, beyond the paper, the sample standard deviation and a 95 %
confidence interval of the mean from Student's t distribution.

The paper reports ``J1`` and ``J2`` of the four fingers and ``J1`` of the thumb, since the
last segment of a finger follows from the others. Here every segment is reported,
including the last (``J3 = 1 - J1 - J2`` per image; thumb ``J2 = 1 - J1``), so a caller
can place every joint of a finger without redoing that arithmetic.

Cohorts: ``all``; ``sex:<value>`` for each sex in the metadata; ``age:<band>`` for each
band of :data:`AGE_BANDS` holding an image with an age, as the paper's future work asks.

The paper errs twice; :func:`paper_discrepancies` recomputes both from its Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from importlib import resources

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from handdb.errors import ClipDataError, HanddbError, ParameterError, UnknownNameError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.xray import SEGMENTS, read_xray
from handdb.store import tables

#: Confidence level of the interval around each mean ratio.
CONFIDENCE = 0.95

#: Age bands, ``(label, lowest age in years)``; a band runs up to the next one's lowest.
AGE_BANDS: tuple[tuple[str, float], ...] = (
    ("0-17", 0.0), ("18-39", 18.0), ("40-59", 40.0), ("60+", 60.0),
)

#: The cohort of every image.
ALL_COHORT = "all"

#: The paper's Table 1, shipped as package data.
TABLE1_RESOURCE = "chaudhry_table1.xray.csv"

#: Decimals the paper prints its ratios with.
PAPER_DECIMALS = 4

#: The X-ray segment of a phalanx bone, by the roles of its parent and child joints.
SEGMENT_OF_ROLES: dict[tuple[str, str], str] = {
    ("mcp", "pip"): "J1", ("pip", "dip"): "J2", ("dip", "tip"): "J3",
    ("mcp", "ip"): "J1", ("ip", "tip"): "J2",
}


@cache
def table1_measurements() -> pa.Table:
    """Return the paper's Table 1 (five right-hand images 1a-1e) as ``xray_measurements``."""
    with resources.as_file(resources.files("handdb") / "data" / TABLE1_RESOURCE) as path:
        measurements, refused = read_xray(path)
    if refused:
        raise HanddbError(f"the shipped {TABLE1_RESOURCE} is damaged: {refused[0]}")
    return measurements


def relative_lengths(measurements: pa.Table, decimals: int | None = None) -> pa.Table:
    """Return each segment's length over its finger's total length, per image.

    Parameters
    ----------
    measurements
        Table ``xray_measurements``; every (image, finger) it holds is complete, as
        :func:`handdb.ingest.xray.read_xray` guarantees.
    decimals
        Round each ratio to this many decimals, as the paper does before averaging;
        ``None`` keeps full precision.

    Returns
    -------
    pa.Table
        The columns ``source_file, image_id, finger, segment, sex, age`` of
        ``measurements`` plus ``total`` (the finger's length, the file's unit) and
        ``ratio`` (dimensionless). Images are told apart by file and id.
    """
    finger_keys = ["source_file", "image_id", "finger"]
    totals = measurements.group_by(finger_keys).aggregate([("length", "sum")])
    joined = measurements.join(totals, keys=finger_keys)
    total = joined.column("length_sum")
    ratio = pc.divide(joined.column("length"), total)
    return pa.table({
        "source_file": joined.column("source_file"),
        "image_id": joined.column("image_id"),
        "finger": joined.column("finger"),
        "segment": joined.column("segment"),
        "sex": joined.column("sex"),
        "age": joined.column("age"),
        "total": total,
        "ratio": ratio if decimals is None else pc.round(ratio, decimals),
    })


def _age_band(age: pa.ChunkedArray) -> pa.Array:
    """Label of the :data:`AGE_BANDS` band of each age (years), null where none."""
    values = age.to_numpy(zero_copy_only=False).astype(float)
    labels = np.array([label for label, _ in AGE_BANDS] + [None], dtype=object)
    edges = np.array([low for _, low in AGE_BANDS[1:]])
    band = np.where(np.isnan(values), len(AGE_BANDS), np.searchsorted(edges, values, "right"))
    return pa.array(labels[band], type=pa.string())


def _cohort_rows(relative: pa.Table) -> pa.Table:
    """One copy of each ratio per cohort its image belongs to."""
    cohorts = [relative.append_column("cohort", pa.array([ALL_COHORT] * relative.num_rows))]
    sex = relative.column("sex")
    cohorts.append(relative.append_column("cohort", pc.binary_join_element_wise("sex:", sex, "")))
    band = _age_band(relative.column("age"))
    cohorts.append(relative.append_column("cohort", pc.binary_join_element_wise("age:", band, "")))
    stacked = pa.concat_tables(cohorts)
    return stacked.filter(pc.is_valid(stacked.column("cohort")))


def joint_ratios(measurements: pa.Table, decimals: int | None = PAPER_DECIMALS) -> pa.Table:
    """Compute the statistics of relative segment lengths per cohort, finger and segment.

    Parameters
    ----------
    measurements
        Table ``xray_measurements``.
    decimals
        Each image's ratio is rounded to this many decimals before the statistics, as
        the paper prints and uses them (four), so that Table 1 gives the paper's figures
        exactly: its index J1 range 0.5047 - 0.4728 = 0.0319 is 0.03196 unrounded. The
        rounding moves a ratio by at most 5e-5, far below the spread between hands.
        ``None`` keeps full precision.

    Returns
    -------
    pa.Table
        Table ``joint_ratios``: ``n`` images, ``mean``, ``min``, ``max``, ``range`` (the
        paper's eqs. 5-10), ``std`` (sample, ``ddof=1``) and the 95 % t interval
        ``ci_low``/``ci_high`` of the mean; the last three are null where ``n < 2``.
    """
    if measurements.num_rows == 0:
        return tables.empty("joint_ratios")
    grouped = _cohort_rows(relative_lengths(measurements, decimals)).group_by(
        ["cohort", "finger", "segment"]).aggregate([
            ("ratio", "count"), ("ratio", "mean"), ("ratio", "min"), ("ratio", "max"),
            ("ratio", "stddev", pc.VarianceOptions(ddof=1)),
        ])
    n = grouped.column("ratio_count").to_numpy()
    mean = grouped.column("ratio_mean").to_numpy()
    std = grouped.column("ratio_stddev").to_numpy(zero_copy_only=False).astype(float)
    # Student's t quantile; scipy.special, as scipy.stats takes a second to import
    from scipy.special import stdtrit

    with np.errstate(invalid="ignore", divide="ignore"):
        half_width = stdtrit(n - 1, 0.5 + CONFIDENCE / 2) * std / np.sqrt(n)
    defined = n >= 2
    lowest = grouped.column("ratio_min").to_numpy()
    highest = grouped.column("ratio_max").to_numpy()
    return tables.from_columns("joint_ratios", {
        "cohort": grouped.column("cohort"),
        "finger": grouped.column("finger"),
        "segment": grouped.column("segment"),
        "n": n,
        "mean": mean,
        "min": lowest,
        "max": highest,
        "range": highest - lowest,
        "std": pa.array(np.where(defined, std, np.nan), from_pandas=True),
        "ci_low": pa.array(np.where(defined, mean - half_width, np.nan), from_pandas=True),
        "ci_high": pa.array(np.where(defined, mean + half_width, np.nan), from_pandas=True),
    })


@cache
def table1_ratios() -> pa.Table:
    """Table ``joint_ratios`` of the paper's Table 1 (:func:`table1_measurements`).

    Worked out once per process: every clip of a build without X-ray tables of its own
    sizes its phalanges by it.
    """
    return joint_ratios(table1_measurements())


def finger_ratios(ratios: pa.Table, finger: str, cohort: str = ALL_COHORT) -> pa.Table:
    """Return the rows of ``ratios`` (table ``joint_ratios``) for one finger and cohort.

    Raises
    ------
    UnknownNameError
        If ``finger`` is not a finger.
    ClipDataError
        If the table lacks a segment of the finger for that cohort.
    """
    if finger not in SEGMENTS:
        raise UnknownNameError("finger", finger, tuple(SEGMENTS))
    rows = ratios.filter(pc.and_(pc.equal(ratios.column("cohort"), cohort),
                                 pc.equal(ratios.column("finger"), finger)))
    found = rows.column("segment").to_pylist()
    missing = [s for s in SEGMENTS[finger] if s not in found]
    if missing:
        raise ClipDataError(f"joint ratios of cohort '{cohort}' lack {finger} "
                            f"{', '.join(missing)}")
    return rows.sort_by("segment")


def phalanx_segments(skeleton: Skeleton) -> tuple[str | None, ...]:
    """Name the X-ray segment (``J1``..``J3``) of the bone ending at each joint.

    Returns
    -------
    tuple of str or None
        ``(J,)``: the segment of each phalanx bone (named by its child joint), ``None``
        for the root and for palm bones and metacarpals, which X-rays of phalanges
        do not measure.
    """
    return tuple(
        None if parent < 0 else SEGMENT_OF_ROLES.get((skeleton.roles[parent], role))
        for parent, role in zip(skeleton.parents, skeleton.roles, strict=True)
    )


def bone_ratios(skeleton: Skeleton, ratios: pa.Table,
                cohort: str = ALL_COHORT) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of the relative length of every phalanx bone.

    Parameters
    ----------
    skeleton
        The skeleton whose bones to look up.
    ratios
        Table ``joint_ratios``.
    cohort
        The cohort whose statistics to use.

    Returns
    -------
    mean, std
        ``(J,) float64`` each, relative to the total length of the bone's finger
        (dimensionless); NaN for bones that are not phalanges or whose finger lacks a
        segment in ``ratios`` (``std`` also where ``n < 2``).
    """
    rows = ratios.filter(pc.equal(ratios.column("cohort"), cohort))
    lookup = {(f, s): (m, sd) for f, s, m, sd in zip(
        rows.column("finger").to_pylist(), rows.column("segment").to_pylist(),
        rows.column("mean").to_pylist(), rows.column("std").to_pylist(), strict=True)}
    complete = {f for f in SEGMENTS if all((f, s) in lookup for s in SEGMENTS[f])}
    values = [
        lookup[(finger, segment)] if segment is not None and finger in complete
        else (None, None)
        for finger, segment in zip(skeleton.fingers, phalanx_segments(skeleton), strict=True)
    ]
    mean, std = (np.array([np.nan if v is None else v for v in column], dtype=float)
                 for column in zip(*values, strict=True))
    return mean, std


@dataclass(frozen=True)
class SegmentPlacement:
    """Expected length of one segment of a finger of known total length.

    Lengths are in the unit of the total; ``start`` is the mean distance from the
    finger's root to the joint the segment starts at.
    """

    segment: str
    mean: float
    min: float
    max: float
    range: float
    start: float


def place_joints(finger: str, total: float, ratios: pa.Table,
                 cohort: str = ALL_COHORT) -> tuple[SegmentPlacement, ...]:
    """Place the joints of a finger of known length: segment lengths with min/max bands.

    The paper's application: a finger model of total length ``total`` gets segment
    ``k`` of mean length ``mean_k * total``, lying between ``min_k * total`` and
    ``max_k * total``.

    Parameters
    ----------
    finger
        ``thumb``, ``index``, ``middle``, ``ring`` or ``little``.
    total
        The finger's total length (root joint to tip), any unit.
    ratios
        Table ``joint_ratios``.
    cohort
        The cohort whose statistics to use.

    Returns
    -------
    tuple of SegmentPlacement
        One per segment, from the root of the finger.
    """
    if not np.isfinite(total) or total <= 0:
        raise ParameterError(f"a finger's total length must be greater than 0, got {total}")
    rows = finger_ratios(ratios, finger, cohort)
    mean = rows.column("mean").to_numpy() * total
    starts = np.concatenate([[0.0], np.cumsum(mean)[:-1]])
    return tuple(
        SegmentPlacement(segment=segment, mean=float(m), min=float(lo * total),
                         max=float(hi * total), range=float(r * total), start=float(s))
        for segment, m, lo, hi, r, s in zip(
            rows.column("segment").to_pylist(), mean, rows.column("min").to_numpy(),
            rows.column("max").to_numpy(), rows.column("range").to_numpy(), starts,
            strict=True)
    )


@dataclass(frozen=True)
class Discrepancy:
    """A figure the paper prints that its own data do not give."""

    where: str
    quantity: str
    printed: float
    recomputed: float
    decimals: int
    explanation: str

    def __str__(self) -> str:
        return (f"{self.where}, {self.quantity}: the paper prints "
                f"{self.printed:.{self.decimals}f}, its own data give "
                f"{self.recomputed:.{self.decimals}f} ({self.explanation})")


#: What the paper prints for the two figures it gets wrong.
_PRINTED_INDEX_J1_MEAN = 0.4946
_PRINTED_1A_INDEX_J3 = 169.97


def paper_discrepancies(measurements: pa.Table | None = None) -> tuple[Discrepancy, ...]:
    """List the two places where Chaudhry et al. contradict their own Table 1.

    1. Eq. (6) prints the mean relative J1 of the index finger as 0.4946, yet the mean
       of the five ratios it lists (0.4865, 0.4728, 0.4862, 0.5047, 0.4728) is 0.4846,
       which Table 1 also gives; the placement example repeats the wrong 494.6.
    2. Eqs. (3)-(4) take image 1a's index J3 as 169.97, where Table 1 prints 169.67.
       The text's ratio 0.4865 follows from 169.97; Table 1 gives 0.4867. Either value
       leaves the mean at 0.4846.

    Parameters
    ----------
    measurements
        Table ``xray_measurements`` holding the paper's Table 1; the shipped copy by
        default.
    """
    data = table1_measurements() if measurements is None else measurements
    ratios = joint_ratios(data)
    index_j1 = ratios.filter(pc.and_(pc.equal(ratios.column("cohort"), ALL_COHORT),
                                     pc.equal(ratios.column("finger"), "index")))
    mean_j1 = index_j1.filter(pc.equal(index_j1.column("segment"), "J1")).column("mean")[0]
    j3 = data.filter(pc.and_(pc.and_(pc.equal(data.column("image_id"), "1a"),
                                     pc.equal(data.column("finger"), "index")),
                             pc.equal(data.column("segment"), "J3"))).column("length")[0]
    return (
        Discrepancy(
            where="eq. (6)", quantity="mean relative J1 of the index finger",
            printed=_PRINTED_INDEX_J1_MEAN, recomputed=mean_j1.as_py(),
            decimals=PAPER_DECIMALS,
            explanation="the mean of the five ratios the paper lists itself; the "
                        "placement example's 494.6 inherits the error, 484.6 is right"),
        Discrepancy(
            where="eqs. (3)-(4)", quantity="index J3 of image 1a",
            printed=_PRINTED_1A_INDEX_J3, recomputed=j3.as_py(), decimals=2,
            explanation="Table 1's value; the text's 169.97 gives J1 ratio 0.4865, "
                        "Table 1's gives 0.4867, and both leave the mean at 0.4846"),
    )


def ratios_markdown(ratios: pa.Table, cohort: str = ALL_COHORT) -> str:
    """A markdown report of the joint ratios of ``cohort`` and the paper's discrepancies.

    Parameters
    ----------
    ratios
        Table ``joint_ratios``.
    cohort
        The cohort to tabulate.
    """
    rows = ratios.filter(pc.equal(ratios.column("cohort"), cohort)).to_pylist()
    lines = [f"## Joint ratios (cohort {cohort})", "",
             "| finger | segment | n | mean | min | max | range | 95 % CI |",
             "|---|---|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        interval = ("" if r["ci_low"] is None
                    else f"{r['ci_low']:.4f} - {r['ci_high']:.4f}")
        lines.append(f"| {r['finger']} | {r['segment']} | {r['n']} | {r['mean']:.4f} | "
                     f"{r['min']:.4f} | {r['max']:.4f} | {r['range']:.4f} | {interval} |")
    lines += ["", "Where Chaudhry et al. contradict their own Table 1:", ""]
    lines += [f"- {d}" for d in paper_discrepancies()]
    return "\n".join(lines) + "\n"
