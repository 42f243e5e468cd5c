"""Shared reading of long-form CSV files: one row per (frame, joint), named columns.

Used by the canonical track format (``frame,joint,u,v[,confidence]``) and the two 3D
formats, ground truth and 3D markers (``frame,joint,x,y,z``).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import (
    DelimitedTable,
    TextLines,
    check_separator,
    read_bytes,
    read_delimited,
    split_header,
    unnamed_placeholders,
    write_csv,
)
from handdb.ingest.limits import quoted
from handdb.ingest.observations import Positions, resolve_names, single_file_rows


def read_long_csv(path: Path, required: tuple[str, ...], optional: tuple[str, ...] = (),
                  types: Mapping[str, pa.DataType] | None = None) -> DelimitedTable:
    """Read a CSV whose header names ``required`` and possibly ``optional`` columns.

    ``types`` names the columns to parse while reading, as
    :func:`~handdb.ingest.delimited.read_delimited` takes them.

    Raises
    ------
    InputError
        For an empty file, fields separated by semicolons or tabs, a header that lacks a
        required column or names an unknown or repeated one, a file without data rows, or
        a row with the wrong number of cells. Columns with an empty header cell (pandas'
        index, a spreadsheet's trailing empty columns) are read but never used.
    """
    data = read_bytes(path)
    [(header_line, start, end)] = TextLines.leading(data, 1)
    header = split_header(data[start:end], ",")
    check_separator(path, header, header_line)
    accepted = ", ".join(required) + "".join(f"[, {name}]" for name in optional)
    for name in header:
        if name and name not in required + optional:
            raise InputError(path, f"unknown column {quoted(name)}; the header must be "
                             f"{accepted}", line=header_line, field=name)
        if name and header.count(name) > 1:
            raise InputError(path, "column named twice in the header", line=header_line,
                             field=name)
    for name in required:
        if name not in header:
            raise InputError(path, f"the header lacks column '{name}'; it must be {accepted}",
                             line=header_line, field=name)
    table = read_delimited(path, data, names=unnamed_placeholders(header), header_lines=1,
                           types=types)
    if not table.n_rows:
        raise InputError(path, "has a header but no data rows", line=header_line)
    return table


def joint_rows(table: DelimitedTable, column: str, spec: ClipSpec, skeleton: Skeleton,
               ) -> tuple[DelimitedTable, np.ndarray, frozenset[str]]:
    """Resolve the joint names in ``column`` and drop the rows of ignored names.

    Names resolve by :func:`~handdb.ingest.observations.resolve_names`; the rows of
    names the sidecar's ``joint_map`` ignores are dropped before any other check.

    Returns
    -------
    table
        The rows kept.
    joint
        ``(N,) int64``, the joint index of each row kept.
    names
        Every name in ``column``.

    Raises
    ------
    InputError
        At the first row of a name that is unknown or maps to a joint another name has.
    """
    names, codes = table.dictionary(column)
    indices = resolve_names(names, spec, skeleton, table.path,
                            lambda k: (int(table.line[np.argmax(codes == k)]), column))
    joint = indices[codes]
    keep = joint >= 0
    if keep.all():
        return table, joint, frozenset(names)
    return table.take(keep), joint[keep], frozenset(names)


#: Columns of the long-form 3D formats (ground truth, 3D markers).
POSITION_COLUMNS = ("frame", "joint", "x", "y", "z")

#: What the long-form formats' frame and coordinate columns hold, to parse while reading.
FRAME_TYPE = {"frame": pa.int64()}
POSITION_TYPES = FRAME_TYPE | dict.fromkeys("xyz", pa.float64())


def read_positions(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read a long-form 3D CSV file (``frame,joint,x,y,z``) into positions, clip units.

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell: an unknown column, a frame
        that is not a whole number or is negative, an unknown joint, an empty or
        non-numeric coordinate, a joint given twice in a frame. Rows of names the
        ``joint_map`` ignores are dropped first.
    """
    path = Path(path)
    table, joint, names = joint_rows(read_long_csv(path, POSITION_COLUMNS,
                                                   types=POSITION_TYPES), "joint", spec,
                                     skeleton)
    frame = table.frames("frame")
    source, files = single_file_rows(path, table.n_rows)
    return Positions(
        frame=frame,
        joint=joint,
        xyz=np.stack([table.numbers(axis, allow_empty=False) for axis in "xyz"], axis=1),
        line=table.line,
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
        names=names,
    )


def write_positions(path: str | Path, xyz: np.ndarray, skeleton: Skeleton) -> None:
    """Write a long-form 3D CSV file: one row per finite point.

    Parameters
    ----------
    path
        The file to write.
    xyz
        ``(T, J, 3) float64`` in the clip's units; NaN points get no row.
    skeleton
        The skeleton ordering the joint axis.
    """
    frame, joint = np.nonzero(finite_points(xyz))
    columns = {"frame": pa.array(frame, pa.int64()),
               "joint": pa.array(np.asarray(skeleton.joints)[joint])}
    columns.update({axis: pa.array(xyz[frame, joint, k]) for k, axis in enumerate("xyz")})
    write_csv(path, columns)
