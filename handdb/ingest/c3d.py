"""3D marker tracks in C3D files, ``<clip_id>.c3d``, read with the ``c3d`` package.

A C3D file holds labelled 3D points per frame. Each label (blanks and NULs around it
dropped) is a joint by the one ``joint_map`` rule of
:func:`~handdb.ingest.observations.resolve_names`: a capture's extra markers must be
mapped to ``null``, or ignored all at once with ``"*": null``. A point the capture lost in
a frame (negative residual; non-finite coordinates, and coordinates exactly 0, 0, 0,
which exporters without residuals write for a gap, count as lost) is missing; a residual
of 0 (a point the capture software modelled) is kept. Coordinates are converted from the
file's ``POINT:UNITS`` (one unit for the file or one per point, all alike; millimetres
when absent, the C3D default) to the clip's units. Frames count from the file's first
frame, here 0; ``POINT:RATE`` must be the sidecar's ``fps``.

The file is checked before the ``c3d`` package reads it (its header, parameter section
and data must lie inside the file), every error of the package becomes an
:class:`~handdb.errors.InputError`, and a file holding fewer frames than its header says
(a truncated export) is refused. ANALOG, FORCE_PLATFORM, ROTATION (segment orientations,
stored after the points by ezc3d and Vicon) and other groups are ignored; a file without 3D
points (force plates or rotations only) is refused, saying what it holds.
"""

from __future__ import annotations

import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import c3d
import numpy as np

from handdb.clip import METERS_PER_UNIT, ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.limits import (
    MAX_FRAMES,
    check_recorded_rate,
    checked_size,
    frame_limit_reason,
)
from handdb.ingest.observations import Positions, resolve_names, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat

#: The C3D parameter that names the point units.
UNITS_PARAMETER = "POINT:UNITS"

#: The C3D parameter that names the points.
LABELS_PARAMETER = "POINT:LABELS"

#: Point rate written when a clip's frame rate is not given.
DEFAULT_POINT_RATE = 120.0

#: Bytes in a C3D block; the header is the first block.
BLOCK_BYTES = 512

#: The second byte of every C3D file.
C3D_MARK = 0x50

#: The processor byte of big-endian (MIPS) files; Intel (84) and DEC (85) are little-endian.
BIG_ENDIAN_PROCESSOR = 86

#: Units when a file has no ``POINT:UNITS`` (the C3D standard's default).
DEFAULT_UNITS = "mm"

#: Everything the ``c3d`` package raises on a damaged file (it asserts on some checks,
#: which ``python -O`` removes: the pre-checks here do not rely on them).
C3D_ERRORS = (struct.error, AssertionError, AttributeError, ValueError, KeyError, IndexError,
              EOFError, OverflowError, TypeError, UnicodeDecodeError, ZeroDivisionError)


@dataclass(frozen=True)
class _Points:
    """The 3D points of a C3D file: labels, ``(T, N, 4)`` x, y, z, residual, units."""

    labels: list[str]
    points: np.ndarray
    units: str
    rate: float


def _unreadable(path: Path, exc: Exception) -> InputError:
    detail = str(exc).strip() or type(exc).__name__
    return InputError(path, f"is not a readable C3D file ({detail})")


def _precheck(path: Path) -> None:
    """Refuse a file too short for its own header, parameter section or data start."""
    size = checked_size(path)
    if size < BLOCK_BYTES:
        raise InputError(path, f"is not a C3D file (it is {size} bytes; a C3D header alone is "
                         f"{BLOCK_BYTES})")
    with path.open("rb") as handle:
        header = handle.read(BLOCK_BYTES)
        if header[1] != C3D_MARK:
            raise InputError(path, "is not a C3D file (its second byte is not the C3D mark "
                             f"0x{C3D_MARK:X})")
        parameter_start = (max(header[0], 1) - 1) * BLOCK_BYTES
        handle.seek(parameter_start)
        parameter_head = handle.read(4)
    if len(parameter_head) < 4:
        raise InputError(path, f"ends before its parameter section ({size} of at least "
                         f"{parameter_start + 4} bytes); the file is truncated")
    parameter_end = parameter_start + parameter_head[2] * BLOCK_BYTES
    if parameter_end > size:
        raise InputError(path, f"ends inside its parameter section ({size} of at least "
                         f"{parameter_end} bytes); the file is truncated")
    order = ">" if parameter_head[3] == BIG_ENDIAN_PROCESSOR else "<"
    data_start = (max(struct.unpack(order + "H", header[16:18])[0], 1) - 1) * BLOCK_BYTES
    if data_start > size:
        raise InputError(path, f"ends before its data ({size} of at least {data_start} "
                         "bytes); the file is truncated")


def _no_points_reason(reader: c3d.Reader) -> str:
    """Say what a C3D file without 3D points holds instead."""
    analog = reader.get("ANALOG:USED")
    plates = reader.get("FORCE_PLATFORM:USED")
    rotations = reader.get("ROTATION:USED")
    parts = []
    if analog is not None and analog.int16_value > 0:
        rate = reader.get("ANALOG:RATE")
        at = f" at {rate.float_value:g} Hz" if rate is not None else ""
        parts.append(f"{analog.int16_value} analog channels{at}")
    if plates is not None and plates.int16_value > 0:
        parts.append(f"{plates.int16_value} force plates")
    if rotations is not None and rotations.int16_value > 0:
        parts.append(f"{rotations.int16_value} rotations (segment orientations, which "
                     "handdb does not read)")
    held = f" (it has {' and '.join(parts)})" if parts else ""
    return (f"holds no 3D points{held}; handdb reads marker trajectories: export the "
            "markers to C3D")


def _labels(reader: c3d.Reader, path: Path, n_points: int) -> list[str]:
    """The point labels, blanks and NULs stripped; one per point."""
    param = reader.get(LABELS_PARAMETER)
    labels = [] if param is None else [str(label).strip(" \0") for label in
                                       np.atleast_1d(param.string_array)]
    if len(labels) < n_points:
        raise InputError(path, f"has {len(labels)} labels for {n_points} points",
                         field=LABELS_PARAMETER)
    labels = labels[:n_points]
    for k, label in enumerate(labels):
        if not label:
            raise InputError(path, f"point {k + 1} has an empty label", field=LABELS_PARAMETER)
        if label in labels[:k]:
            raise InputError(path, f"label '{label}' is given to two points",
                             field=LABELS_PARAMETER)
    return labels


def _units(reader: c3d.Reader, path: Path, labels: list[str]) -> str:
    """The one unit of every point: ``POINT:UNITS`` once, or once per point all alike."""
    param = reader.get(UNITS_PARAMETER)
    if param is None:
        return DEFAULT_UNITS
    given = ([str(unit).strip(" \0") for unit in np.atleast_1d(param.string_array)]
             if len(param.dimensions) > 1 else [param.string_value.strip(" \0")])
    units = [unit.lower() for unit in given]
    for unit, raw in zip(units, given, strict=True):
        if unit not in METERS_PER_UNIT:
            raise InputError(path, f"point units '{raw}' are not one of "
                             f"{', '.join(METERS_PER_UNIT)}", field=UNITS_PARAMETER)
    if len(set(units)) > 1:
        other = next(k for k, unit in enumerate(units) if unit != units[0])
        raise InputError(path, f"points use different units ({units[0]} for {labels[0]}, "
                         f"{units[other]} for {labels[min(other, len(labels) - 1)]})",
                         field=UNITS_PARAMETER)
    return units[0]


def _check_complete(reader: c3d.Reader, path: Path, n_frames: int) -> None:
    """Refuse a file whose data ends before the frames its header promises."""
    size = path.stat().st_size
    data_start = (int(reader.header.data_block) - 1) * BLOCK_BYTES
    word = 4 if reader.point_scale < 0 else 2
    frame_bytes = word * (4 * int(reader.point_used)
                          + int(reader.analog_used) * max(int(reader.analog_per_frame), 0))
    needed = data_start + n_frames * frame_bytes
    if size < needed:
        held = max(size - data_start, 0) // frame_bytes
        raise InputError(path, f"holds {held} frames of POINT data, but its header says "
                         f"{n_frames} (the file is {size} bytes, {needed} needed): it is "
                         "truncated; export it again", field="POINT:FRAMES")


def _read_points(path: Path) -> _Points:
    """Read the labelled points of a C3D file, refusing damaged or incomplete files."""
    _precheck(path)
    try:
        with path.open("rb") as handle, warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            reader = c3d.Reader(handle)
            used = reader.get("POINT:USED")
            if reader.get("POINT") is None or used is None or used.int16_value <= 0:
                raise InputError(path, _no_points_reason(reader), field="POINT:USED")
            n_frames = int(reader.frame_count)
            if n_frames > MAX_FRAMES:
                raise InputError(path, frame_limit_reason(n_frames - 1), field="POINT:FRAMES")
            if n_frames <= 0:
                raise InputError(path, "holds no frames", field="POINT:FRAMES")
            _check_complete(reader, path, n_frames)
            labels = _labels(reader, path, int(reader.point_used))
            units = _units(reader, path, labels)
            rate = float(reader.point_rate)
            frames = [points[:, :4].astype(np.float64) for _, points, _ in reader.read_frames()]
    except C3D_ERRORS as exc:
        raise _unreadable(path, exc) from None
    if len(frames) < n_frames:
        raise InputError(path, f"holds {len(frames)} frames of POINT data, but its header "
                         f"says {n_frames}: it is truncated; export it again",
                         field="POINT:FRAMES")
    return _Points(labels=labels, points=np.stack(frames), units=units, rate=rate)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read the labelled markers of a C3D file into long-form positions (clip units).

    Raises
    ------
    InputError
        If the file is not C3D or is damaged or truncated, holds no 3D points or no
        frames, names units other than mm, cm, m or in (or different units per point),
        has a label the ``joint_map`` rule refuses, or records a ``POINT:RATE`` other than
        the sidecar's ``fps``.
    """
    path = Path(path)
    points = _read_points(path)
    check_recorded_rate(points.rate, spec.fps, path, "POINT:RATE", sidecar=spec.path,
                        clip_id=spec.clip_id)
    joints = resolve_names(points.labels, spec, skeleton, path,
                           lambda k: (None, LABELS_PARAMETER))
    known = np.flatnonzero(joints >= 0)
    xyz_known = points.points[:, known, :3]
    present = ((points.points[:, known, 3] >= 0) & finite_points(xyz_known)
               & (xyz_known != 0).any(axis=-1))
    frame, column = np.nonzero(present)
    scale = METERS_PER_UNIT[points.units] / spec.meters_per_unit
    xyz = points.points[frame, known[column], :3] * scale
    source, files = single_file_rows(path, len(frame))
    return Positions(
        frame=frame.astype(np.int64),
        joint=joints[known][column],
        xyz=xyz,
        line=np.zeros(len(frame), dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=len(points.points),
        names=frozenset(points.labels),
        fields=dict.fromkeys("xyz", "POINT:DATA {joint}"),
        joint_names=_joint_names(points.labels, joints, skeleton),
    )


def _joint_names(labels: list[str], joints: np.ndarray, skeleton: Skeleton) -> tuple[str, ...]:
    """The file's label of each skeleton joint (canonical names for joints it lacks)."""
    names = list(skeleton.joints)
    for label, joint in zip(labels, joints, strict=True):
        if joint >= 0:
            names[joint] = label
    return tuple(names)


def write(path: str | Path, markers: np.ndarray, skeleton: Skeleton, *, units: str = "mm",
          point_rate: float = DEFAULT_POINT_RATE) -> None:
    """Write markers as a C3D file (floating point, labelled by canonical joint names).

    Parameters
    ----------
    path
        The file to write.
    markers
        ``(T, J, 3) float64`` in ``units``; NaN markers are written as missing.
    skeleton
        The skeleton ordering the joint axis.
    units
        Units of ``markers``, written to ``POINT:UNITS``.
    point_rate
        Frames per second.
    """
    writer = c3d.Writer(point_rate=point_rate, point_units=units)
    writer.set_point_labels(list(skeleton.joints))
    missing = ~finite_points(markers)
    points = np.zeros(markers.shape[:2] + (5,), dtype=np.float32)
    points[..., :3] = np.where(missing[..., None], 0.0, markers)
    points[..., 3] = np.where(missing, -1.0, 0.0)
    no_analog = np.zeros((0, 0), dtype=np.float32)
    writer.add_frames([(frame, no_analog) for frame in points])
    with Path(path).open("wb") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        writer.write(handle)


FORMAT = InputFormat(name="c3d", suffix=".c3d", kind=MARKERS_KIND, read=read, write=write)
