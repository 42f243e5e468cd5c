"""Qualisys Track Manager 3D exports, ``<clip_id>.qtm.tsv`` (3D markers).

QTM's "Motion data (.tsv)" export: tab-separated header lines ``KEY<TAB>value...``
(``NO_OF_FRAMES``, ``NO_OF_MARKERS``, ``FREQUENCY``, ``DATA_INCLUDED``, ``MARKER_NAMES``
required or checked; ``TRAJECTORY_TYPES``, ``EVENT``, ``TIME_STAMP``, ... ignored), an
optional column header ``Frame, Time, <name> X, <name> Y, <name> Z, ...`` in
``MARKER_NAMES`` order, then one row per frame: ``Frame`` (consecutive, here counted from
0) and ``Time``, when the column header has them, then X, Y, Z of every marker in
millimetres, in the lab's frame. A marker QTM lost in a frame has all three cells
``nan`` (or ``NULL``, or empty); a row whose cells are cut, or fewer rows than
``NO_OF_FRAMES``, is a truncated export and refused.

Marker names resolve by the one ``joint_map`` rule
(:func:`~handdb.ingest.observations.resolve_names`): the glove's extra markers are mapped
to ``null``, or ignored with ``"*": null``. ``FREQUENCY`` must be the sidecar's ``fps``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from handdb.clip import METERS_PER_UNIT, ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import DelimitedTable, TextLines, read_bytes, read_delimited
from handdb.ingest.limits import MAX_FRAMES, check_recorded_rate, frame_limit_reason, quoted
from handdb.ingest.observations import Positions, resolve_names, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat

#: QTM writes millimetres.
QTM_UNITS = "mm"

#: Header keys a 3D export must have.
REQUIRED_KEYS = ("NO_OF_FRAMES", "NO_OF_MARKERS", "FREQUENCY", "MARKER_NAMES")

#: Header keys that may repeat (one line per event).
REPEATED_KEYS = ("EVENT",)

#: Cells (lower case) QTM writes for a coordinate of a lost marker.
MISSING_CELLS = ("nan", "null", "")

#: The columns before the coordinates in the column header.
FRAME_COLUMNS = ("Frame", "Time")

#: A header key: upper-case letters, digits and underscores.
HEADER_KEY = re.compile(r"[A-Z][A-Z0-9_]*")

AXES = ("X", "Y", "Z")


@dataclass(frozen=True)
class _Header:
    """The header lines of an export: each key's line and cells, and where data starts."""

    keys: dict[str, tuple[int, list[str]]]
    columns_line: int | None
    header_lines: int


def _line_cells(data: bytes, lines: TextLines, n: int) -> list[str]:
    text = data[lines.start[n - 1]:lines.end[n - 1]].decode("utf-8-sig", errors="replace")
    return [cell.strip() for cell in text.split("\t")]


def _header(path: Path, data: bytes, lines: TextLines) -> _Header:
    keys: dict[str, tuple[int, list[str]]] = {}
    count = 0
    for n in lines.nonblank:
        cells = _line_cells(data, lines, int(n))
        if cells[0] == FRAME_COLUMNS[0]:
            return _Header(keys=keys, columns_line=int(n), header_lines=count + 1)
        if not HEADER_KEY.fullmatch(cells[0]):
            break
        if cells[0] in keys and cells[0] not in REPEATED_KEYS:
            raise InputError(path, f"header key {cells[0]} is given twice, here and on line "
                             f"{keys[cells[0]][0]}", line=int(n), field=cells[0])
        keys[cells[0]] = (int(n), cells[1:])
        count += 1
    return _Header(keys=keys, columns_line=None, header_lines=count)


def _whole_value(path: Path, header: _Header, key: str) -> int:
    line, cells = header.keys[key]
    if not cells or not cells[0].isascii() or not cells[0].isdigit() or len(cells[0]) > 9:
        raise InputError(path, f"must be a whole number, got {quoted(' '.join(cells))}",
                         line=line, field=key)
    return int(cells[0])


def _marker_names(path: Path, header: _Header) -> list[str]:
    """The marker names, checked against ``NO_OF_MARKERS``, ``DATA_INCLUDED``, the columns."""
    for key in REQUIRED_KEYS:
        if key not in header.keys:
            raise InputError(path, f"is not a QTM 3D export: its header has no {key} line",
                             line=1, field=key)
    if "DATA_INCLUDED" in header.keys:
        line, cells = header.keys["DATA_INCLUDED"]
        if cells[:1] != ["3D"]:
            raise InputError(path, f"holds {' '.join(cells) or 'no'} data; export 3D "
                             "trajectories", line=line, field="DATA_INCLUDED")
    line, names = header.keys["MARKER_NAMES"]
    names = names[:-1] if names and not names[-1] else names
    n_markers = _whole_value(path, header, "NO_OF_MARKERS")
    if n_markers != len(names):
        raise InputError(path, f"names {len(names)} markers, but NO_OF_MARKERS says "
                         f"{n_markers}", line=line, field="MARKER_NAMES")
    for k, name in enumerate(names):
        if not name:
            raise InputError(path, f"marker {k + 1} has an empty name", line=line,
                             field="MARKER_NAMES")
        if name in names[:k]:
            raise InputError(path, f"marker {quoted(name)} is named twice", line=line,
                             field="MARKER_NAMES")
    return names


def _column_names(path: Path, data: bytes, lines: TextLines, header: _Header,
                  names: list[str]) -> list[str]:
    """The data columns: ``Frame, Time`` (when the column header has them) and X, Y, Z."""
    coordinates = [f"{name} {axis}" for name in names for axis in AXES]
    if header.columns_line is None:
        return coordinates
    expected = list(FRAME_COLUMNS) + coordinates
    cells = _line_cells(data, lines, header.columns_line)
    cells = cells[:-1] if cells and not cells[-1] else cells
    if cells != expected:
        wrong = next((k for k, (a, b) in enumerate(zip(cells, expected, strict=False))
                      if a != b), min(len(cells), len(expected)))
        want = (quoted(expected[wrong]) if wrong < len(expected)
                else f"no column after {quoted(expected[-1])}")
        got = quoted(cells[wrong]) if wrong < len(cells) else "missing"
        raise InputError(path, f"column {wrong + 1} is {got}, expected {want} (the columns "
                         "follow MARKER_NAMES)", line=header.columns_line,
                         field=expected[wrong] if wrong < len(expected) else "Frame")
    return expected


def _frames(table: DelimitedTable) -> np.ndarray:
    """Frame of each row from 0: ``Frame`` minus the first, or the row's position."""
    if FRAME_COLUMNS[0] not in table.columns:
        return np.arange(table.n_rows, dtype=np.int64)
    frame = table.frames(FRAME_COLUMNS[0])
    jump = np.flatnonzero(np.diff(frame) != 1)
    if jump.size:
        row = int(jump[0]) + 1
        raise table.error(row, FRAME_COLUMNS[0], f"frame {frame[row]} follows frame "
                          f"{frame[row - 1]}; a QTM export numbers its frames one by one")
    return frame - frame[0]


def _coordinates(table: DelimitedTable, name: str) -> np.ndarray:
    """``(N, 3)`` mm of one marker, NaN where QTM lost it (all three cells missing)."""
    missing, cleaned = [], {}
    for axis in AXES:
        column = f"{name} {axis}"
        cells = table.columns[column]
        comma = np.flatnonzero(pc.match_substring(cells, ",").to_numpy(zero_copy_only=False))
        if comma.size:
            raise table.error(int(comma[0]), column, f"{quoted(cells[int(comma[0])].as_py())} "
                              "uses a decimal comma; export with '.' as decimal separator")
        lost = pc.is_in(pc.utf8_lower(cells), value_set=pa.array(MISSING_CELLS))
        missing.append(lost.to_numpy(zero_copy_only=False))
        cleaned[column] = pc.if_else(lost, "", cells)
    partial = np.flatnonzero(np.any(missing, axis=0) != np.all(missing, axis=0))
    if partial.size:
        row = int(partial[0])
        axis = next(a for a, lost in zip(AXES, missing, strict=True) if lost[row])
        raise table.error(row, f"{name} {axis}", "is missing but the marker's other "
                          "coordinates are not; a lost marker has all three cells nan")
    values = DelimitedTable(path=table.path, columns=cleaned, line=table.line)
    return np.column_stack([values.numbers(f"{name} {axis}", allow_empty=True)
                            for axis in AXES])


def _check_frequency(path: Path, header: _Header, spec: ClipSpec) -> None:
    line, cells = header.keys["FREQUENCY"]
    try:
        rate = float(cells[0]) if cells else float("nan")
    except ValueError:
        rate = float("nan")
    if not rate > 0 or not np.isfinite(rate):
        raise InputError(path, f"must be a frame rate in Hz, got {quoted(' '.join(cells))}",
                         line=line, field="FREQUENCY")
    check_recorded_rate(rate, spec.fps, path, "FREQUENCY", line=line, sidecar=spec.path,
                        clip_id=spec.clip_id)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read a QTM 3D TSV export into long-form marker positions (clip units).

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell or header line: a missing or
        contradictory header key, a column header that does not follow ``MARKER_NAMES``,
        a cut row or fewer rows than ``NO_OF_FRAMES``, frames not numbered one by one, a
        decimal comma, a marker missing in some of its three cells only, a name the
        ``joint_map`` rule refuses, or a ``FREQUENCY`` other than the sidecar's ``fps``.
    """
    path = Path(path)
    data = read_bytes(path)
    lines = TextLines.of(data)
    header = _header(path, data, lines)
    names = _marker_names(path, header)
    _check_frequency(path, header, spec)
    n_frames = _whole_value(path, header, "NO_OF_FRAMES")
    if n_frames > MAX_FRAMES:
        raise InputError(path, frame_limit_reason(n_frames - 1),
                         line=header.keys["NO_OF_FRAMES"][0], field="NO_OF_FRAMES")
    names_line = header.keys["MARKER_NAMES"][0]
    joints = resolve_names(names, spec, skeleton, path, lambda k: (names_line, "MARKER_NAMES"))
    columns = _column_names(path, data, lines, header, names)
    table = read_delimited(path, data, names=columns, header_lines=header.header_lines,
                           delimiter="\t")
    if table.n_rows != n_frames:
        last = int(lines.nonblank[-1])
        raise InputError(path, f"has {table.n_rows} data rows, but NO_OF_FRAMES says "
                         f"{n_frames}" + (": the file is truncated; export it again"
                                          if table.n_rows < n_frames else ""),
                         line=last, field="NO_OF_FRAMES")
    frame = _frames(table)
    kept = np.flatnonzero(joints >= 0)
    xyz = np.stack([_coordinates(table, names[k]) for k in kept], axis=1)
    row, column = np.nonzero(finite_points(xyz))
    scale = METERS_PER_UNIT[QTM_UNITS] / spec.meters_per_unit
    source, files = single_file_rows(path, row.size)
    joint_names = list(skeleton.joints)
    for k in kept:
        joint_names[joints[k]] = names[k]
    return Positions(
        frame=frame[row],
        joint=joints[kept][column],
        xyz=xyz[row, column] * scale,
        line=table.line[row],
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=n_frames,
        names=frozenset(names),
        fields={axis.lower(): f"{{joint}} {axis}" for axis in AXES},
        joint_names=tuple(joint_names),
    )


FORMAT = InputFormat(name="qtm", suffix=".qtm.tsv", kind=MARKERS_KIND, read=read)
