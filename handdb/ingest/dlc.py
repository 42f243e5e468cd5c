"""DeepLabCut CSV output, ``<clip_id>.dlc.csv``.

Three or four header rows, each led by its label in the first column: ``scorer`` (the
model), optionally ``individuals`` (multi-animal projects; one individual only),
``bodyparts`` and ``coords``. Each body part has an ``x`` and a ``y`` column and
optionally a ``likelihood`` column. Data rows start with the frame index. Body part names
are canonical joint names or names the sidecar's ``joint_map`` maps; an empty ``x``/``y``
is a missing point.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import TextLines, read_bytes, read_delimited, split_header, write_csv
from handdb.ingest.observations import (
    Observations,
    resolve_joints,
    single_file_rows,
    unknown_joint,
)
from handdb.ingest.registry import InputFormat

#: Header rows by their label in the first column; ``individuals`` is optional.
HEADER_LABELS = ("scorer", "individuals", "bodyparts", "coords")

#: The coordinates a body part may have; ``likelihood`` is optional.
COORDS = ("x", "y", "likelihood")


def _header(path: Path, data: bytes, lines: TextLines) -> dict[str, tuple[int, list[str]]]:
    """Return the header rows by label: their line number and cells after the label."""
    first_lines = lines.nonblank[:len(HEADER_LABELS)]
    rows = [split_header(data[lines.start[n - 1]:lines.end[n - 1]], ",") for n in first_lines]
    labels = [cells[0] for cells in rows]
    expected = [label for label in HEADER_LABELS
                if label != "individuals" or labels[1:2] == ["individuals"]]
    for k, label in enumerate(expected):
        if k >= len(labels) or labels[k] != label:
            line = int(first_lines[k]) if k < len(labels) else int(lines.start.size)
            raise InputError(path, "is not a DeepLabCut CSV: the header rows must be labelled "
                             f"{', '.join(expected)} in their first cell; expected '{label}' "
                             "here", line=line, field=label)
    header = {label: (int(first_lines[k]), rows[k][1:]) for k, label in enumerate(expected)}
    widths = {len(cells) for _, cells in header.values()}
    if len(widths) > 1:
        line, _ = min(header.values(), key=lambda row: len(row[1]))
        raise InputError(path, "header rows have different numbers of cells; the file looks "
                         "truncated or hand-edited", line=line)
    return header


def _columns(path: Path, header: dict[str, tuple[int, list[str]]]) -> list[tuple[str, str]]:
    """(body part, coordinate) of every data column after the frame index, validated."""
    if "individuals" in header:
        line, individuals = header["individuals"]
        names = sorted(set(individuals))
        if len(names) > 1:
            raise InputError(path, f"holds {len(names)} individuals ({', '.join(names)}); a "
                             "clip is one hand: keep one individual's columns",
                             line=line, field="individuals")
    bodyparts_line, bodyparts = header["bodyparts"]
    coords_line, coords = header["coords"]
    columns = list(zip(bodyparts, coords, strict=True))
    for bodypart, coord in columns:
        if coord not in COORDS:
            raise InputError(path, f"'{coord}' of body part '{bodypart}' is not one of "
                             f"{', '.join(COORDS)}", line=coords_line, field="coords")
        if columns.count((bodypart, coord)) > 1:
            raise InputError(path, f"body part '{bodypart}' has two '{coord}' columns",
                             line=coords_line, field=bodypart)
    for bodypart in dict.fromkeys(bodyparts):
        for coord in COORDS[:2]:
            if (bodypart, coord) not in columns:
                raise InputError(path, f"body part '{bodypart}' has no '{coord}' column",
                                 line=coords_line, field=bodypart)
    if not columns:
        raise InputError(path, "has no body part columns", line=bodyparts_line,
                         field="bodyparts")
    return columns


def _joints(path: Path, bodyparts: list[str], line: int, spec: ClipSpec,
            skeleton: Skeleton) -> np.ndarray:
    """Joint index of each body part, ``(P,) int64``."""
    joints = resolve_joints(bodyparts, spec, skeleton)
    for bodypart, joint in zip(bodyparts, joints, strict=True):
        if joint < 0:
            raise unknown_joint(str(path), bodypart, spec, skeleton, line=line,
                                field="bodyparts")
    taken: dict[int, str] = {}
    for bodypart, joint in zip(bodyparts, joints, strict=True):
        if joint in taken:
            raise InputError(path, f"body parts '{taken[joint]}' and '{bodypart}' both map to "
                             f"joint '{skeleton.joints[joint]}'", line=line, field="bodyparts")
        taken[joint] = bodypart
    return joints


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a DeepLabCut CSV file.

    Every (data row, body part) becomes a row, its confidence the likelihood (NaN
    without a likelihood column).

    Raises
    ------
    InputError
        Naming the line and the ``bodypart.coord`` column of the first bad cell, or the
        header row at fault.
    """
    path = Path(path)
    data = read_bytes(path)
    lines = TextLines.of(data)
    header = _header(path, data, lines)
    columns = _columns(path, header)
    bodyparts = list(dict.fromkeys(bodypart for bodypart, _ in columns))
    bodyparts_line = header["bodyparts"][0]
    joints = _joints(path, bodyparts, bodyparts_line, spec, skeleton)
    names = ["frame"] + [f"{bodypart}.{coord}" for bodypart, coord in columns]
    table = read_delimited(path, data, names=names, header_lines=len(header))
    if not table.n_rows:
        raise InputError(path, "has header rows but no data rows",
                         line=header["coords"][0])
    frame = table.frames("frame")

    def wide(coord: str) -> np.ndarray:
        """``(N, P)``: ``coord`` of every body part, NaN where empty or absent."""
        return np.stack([table.numbers(f"{bodypart}.{coord}", allow_empty=True)
                         if (bodypart, coord) in columns else np.full(table.n_rows, np.nan)
                         for bodypart in bodyparts], axis=1)

    x, y, likelihood = wide("x"), wide("y"), wide("likelihood")
    source, files = single_file_rows(path, x.size)
    joint_names = list(skeleton.joints)
    for bodypart, joint in zip(bodyparts, joints, strict=True):
        joint_names[joint] = bodypart
    return Observations(
        frame=np.repeat(frame, len(bodyparts)),
        joint=np.tile(joints, table.n_rows),
        u=x.ravel(),
        v=y.ravel(),
        confidence=likelihood.ravel(),
        line=np.repeat(table.line, len(bodyparts)),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
        fields={"u": "{joint}.x", "v": "{joint}.y", "confidence": "{joint}.likelihood"},
        joint_names=tuple(joint_names),
    )


def write(path: str | Path, uv: np.ndarray, confidence: np.ndarray | None,
          skeleton: Skeleton, *, bodyparts: Mapping[str, str] | None = None,
          scorer: str = "handdb", individual: str | None = None) -> None:
    """Write a DeepLabCut CSV file with one data row per frame.

    Parameters
    ----------
    path
        The file to write.
    uv
        ``(T, J, 2) float64``, pixels; NaN where the point is missing (written empty).
    confidence
        ``(T, J) float64`` likelihoods, or ``None`` for no likelihood columns.
    skeleton
        The skeleton ordering the joint axis.
    bodyparts
        Canonical joint name -> body part name to write (the inverse of a sidecar's
        ``joint_map``); joints not in it keep their canonical name.
    scorer
        The scorer (model) name of the first header row.
    individual
        If given, an ``individuals`` header row naming this one individual.
    """
    names = [(bodyparts or {}).get(joint, joint) for joint in skeleton.joints]
    values = {"x": uv[..., 0], "y": uv[..., 1]}
    if confidence is not None:
        values["likelihood"] = confidence
    columns = {"frame": pa.array(np.arange(uv.shape[0]), pa.int64())}
    header_cells = []
    for j, name in enumerate(names):
        for coord in values:
            columns[f"{name}.{coord}"] = pa.array(values[coord][:, j], from_pandas=True)
            header_cells.append((name, coord))
    header = [["scorer"] + [scorer] * len(header_cells)]
    if individual is not None:
        header.append(["individuals"] + [individual] * len(header_cells))
    header.append(["bodyparts"] + [name for name, _ in header_cells])
    header.append(["coords"] + [coord for _, coord in header_cells])
    write_csv(path, columns, header)


FORMAT = InputFormat(name="dlc", suffix=".dlc.csv", kind="tracks", read=read, write=write)
