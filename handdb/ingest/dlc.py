r"""DeepLabCut CSV files, ``<clip_id>.dlc.csv``: analysed videos and labelled data.

Three or four header rows, each led by its label in the first column: ``scorer`` (the
model or labeller), optionally ``individuals`` (multi-animal projects), ``bodyparts`` and
``coords``. Each body part has an ``x`` and a ``y`` column and optionally a ``likelihood``
column. Data rows start with their index: the frame number of an analysed video, or the
image path of labelled data (``labeled-data\<video>\img040.png``); DeepLabCut 2.3 and
later split that path over three index columns (``labeled-data,<video>,img040.png``), its
header rows then having two empty cells after their label.

Sidecar options: ``individual`` names the individual whose columns are read (required
when the ``individuals`` row names more than one; empty cells never count as one);
``frame_from`` says where frame numbers come from: ``"index"`` (the default, the frame
index of an analysed video), ``"image_name"`` (the last run of digits of the image's file
name, ``img040.png`` -> 40; the images must be at least :data:`LABELLED_MIN_SHARE` of the
frames they span) or ``"row"`` (0, 1, 2, ... in row order). Labelled data read by
``"row"`` is a set of independent images, not a track: the clip's
:attr:`~handdb.clip.Clip.sampling` is ``"images"``, and every stage takes each frame on its
own. Body part names
resolve by the one ``joint_map`` rule (:func:`~handdb.ingest.observations.resolve_names`);
an empty ``x``/``y`` is a missing point.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import IMAGES, VIDEO, ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import (
    DelimitedTable,
    TextLines,
    check_separator,
    read_bytes,
    read_delimited,
    split_header,
    write_csv,
)
from handdb.ingest.limits import quoted
from handdb.ingest.observations import Observations, resolve_names, single_file_rows
from handdb.ingest.registry import InputFormat

#: Header rows by their label in the first column; ``individuals`` is optional.
HEADER_LABELS = ("scorer", "individuals", "bodyparts", "coords")

#: The coordinates a body part may have; ``likelihood`` is optional.
COORDS = ("x", "y", "likelihood")

#: Index columns of labelled data written by DeepLabCut 2.3 and later:
#: ``labeled-data``, the video's folder, the image's file name.
SPLIT_INDEX_COLUMNS = 3

#: An index cell that is an image path rather than a frame number.
IMAGE_PATH = re.compile(r"[\\/]|\.(png|jpe?g|bmp|tiff?)$", re.IGNORECASE)

#: The number in an image's file name: its last run of digits.
IMAGE_NUMBER = re.compile(r"(\d+)\D*$")

#: The smallest share of the frames between the first and the last labelled image that
#: must be labelled for ``"frame_from": "image_name"``: DeepLabCut labels a few frames
#: picked from a video, and 20 images over 425 frames are not a track (gap filling would
#: invent the other 405).
LABELLED_MIN_SHARE = 0.2


@dataclass(frozen=True)
class _Layout:
    """The header of a DeepLabCut CSV file.

    Attributes
    ----------
    rows
        Header rows by label: their 1-based line and their cells after the index columns.
    index_columns
        1, or 3 for the split image path of DeepLabCut 2.3 labelled data.
    """

    rows: dict[str, tuple[int, list[str]]]
    index_columns: int


def _header(path: Path, data: bytes, lines: TextLines) -> _Layout:
    """Read and check the header rows."""
    first_lines = lines.nonblank[:len(HEADER_LABELS)]
    rows = [split_header(data[lines.start[n - 1]:lines.end[n - 1]], ",") for n in first_lines]
    check_separator(path, rows[0], int(first_lines[0]))
    labels = [cells[0] for cells in rows]
    expected = [label for label in HEADER_LABELS
                if label != "individuals" or labels[1:2] == ["individuals"]]
    for k, label in enumerate(expected):
        if k >= len(labels) or labels[k] != label:
            line = int(first_lines[k]) if k < len(labels) else int(lines.start.size)
            raise InputError(path, "is not a DeepLabCut CSV: the header rows must be labelled "
                             f"{', '.join(expected)} in their first cell; expected '{label}' "
                             "here", line=line, field=label)
    split = all(len(cells) > SPLIT_INDEX_COLUMNS and cells[1:SPLIT_INDEX_COLUMNS] == ["", ""]
                for cells in rows[:len(expected)])
    index_columns = SPLIT_INDEX_COLUMNS if split else 1
    header = {label: (int(first_lines[k]), rows[k][index_columns:])
              for k, label in enumerate(expected)}
    widths = {len(cells) for _, cells in header.values()}
    if len(widths) > 1:
        line, _ = min(header.values(), key=lambda row: len(row[1]))
        raise InputError(path, "header rows have different numbers of cells; the file looks "
                         "truncated or hand-edited", line=line)
    return _Layout(rows=header, index_columns=index_columns)


def _individual_columns(path: Path, layout: _Layout, spec: ClipSpec) -> np.ndarray:
    """``(C,) bool``: the data columns of the individual the clip is."""
    width = len(layout.rows["bodyparts"][1])
    if "individuals" not in layout.rows:
        if spec.individual is not None:
            raise InputError(spec.path, f"names {quoted(spec.individual)}, but "
                             f"{path.name} has no individuals row (a single-animal file); "
                             "remove the key", field="individual", clip_id=spec.clip_id)
        return np.ones(width, dtype=bool)
    line, cells = layout.rows["individuals"]
    names = list(dict.fromkeys(cell for cell in cells if cell))
    if spec.individual is None and len(names) > 1:
        raise InputError(path, f"holds {len(names)} individuals ({', '.join(names)}); say "
                         f'which hand this clip is with "individual": "{names[0]}" in '
                         f"{Path(spec.path).name}, one sidecar per individual",
                         line=line, field="individuals")
    chosen = spec.individual if spec.individual is not None else names[0] if names else ""
    if chosen not in names:
        raise InputError(spec.path, f"{quoted(chosen)} is not in the individuals row of "
                         f"{path.name} ({', '.join(names)}); names are case-sensitive",
                         field="individual", clip_id=spec.clip_id)
    return np.array([cell == chosen for cell in cells])


def _named_columns(layout: _Layout) -> np.ndarray:
    """``(C,) bool``: the data columns with a body part or a coordinate in the header.

    A column whose header cells are all empty is one a spreadsheet left after the last,
    never read.
    """
    return np.array([bool(bodypart or coord) for bodypart, coord in
                     zip(layout.rows["bodyparts"][1], layout.rows["coords"][1], strict=True)])


def _columns(path: Path, layout: _Layout, chosen: np.ndarray) -> list[tuple[str, str]]:
    """(body part, coordinate) of every chosen data column, validated."""
    bodyparts_line, bodyparts = layout.rows["bodyparts"]
    coords_line, coords = layout.rows["coords"]
    columns = [pair for pair, keep in zip(zip(bodyparts, coords, strict=True), chosen,
                                          strict=True) if keep]
    for bodypart, coord in columns:
        if coord not in COORDS:
            raise InputError(path, f"{quoted(coord)} of body part {quoted(bodypart)} is not "
                             f"one of {', '.join(COORDS)}", line=coords_line, field="coords")
        if columns.count((bodypart, coord)) > 1:
            raise InputError(path, f"body part {quoted(bodypart)} has two '{coord}' columns",
                             line=coords_line, field=bodypart)
    for bodypart in dict.fromkeys(bodypart for bodypart, _ in columns):
        for coord in COORDS[:2]:
            if (bodypart, coord) not in columns:
                raise InputError(path, f"body part {quoted(bodypart)} has no '{coord}' column",
                                 line=coords_line, field=bodypart)
    if not columns:
        raise InputError(path, "has no body part columns", line=bodyparts_line,
                         field="bodyparts")
    return columns


def _image_numbers(table: DelimitedTable, index: list[str]) -> np.ndarray:
    """Frame numbers from the image file names of labelled data, ``(N,) int64``."""
    cells = [table.columns[name].to_pylist() for name in index]
    frames = np.empty(table.n_rows, dtype=np.int64)
    first_row: dict[int, int] = {}
    folders: dict[str, int] = {}
    for row, parts in enumerate(zip(*cells, strict=True)):
        pieces = re.split(r"[\\/]", "/".join(parts))
        match = IMAGE_NUMBER.search(pieces[-1])
        if match is None:
            raise table.error(row, "frame", f"{quoted(pieces[-1])} has no number in its name; "
                              'use "frame_from": "row"')
        folder = pieces[-2] if len(pieces) > 1 else ""
        folders.setdefault(folder, row)
        if len(folders) > 1:
            first = ", ".join(quoted(f) for f in folders)
            raise table.error(row, "frame", f"images come from more than one video folder "
                              f"({first}); a clip is one video: split the file")
        frames[row] = int(match.group(1))
        if frames[row] in first_row:
            raise table.error(row, "frame", f"image number {frames[row]} is also on line "
                              f"{table.line[first_row[frames[row]]]}; keep one row per image")
        first_row[int(frames[row])] = row
    span = int(frames.max()) + 1
    if frames.size < LABELLED_MIN_SHARE * span:
        row = int(np.argmax(frames))
        raise table.error(row, "frame", f"the {frames.size} labelled images span {span} frames "
                          f"of the video (up to image number {frames[row]}): too few to be a "
                          'track; use "frame_from": "row" to read them as consecutive frames')
    return frames


def _first_image(table: DelimitedTable, index: list[str]) -> int | None:
    """The first data row whose index is an image path (labelled data), or ``None``."""
    if len(index) > 1:
        return 0 if table.n_rows else None
    for row, cell in enumerate(table.columns[index[0]].to_pylist()):
        if IMAGE_PATH.search(cell):
            return row
    return None


def _frames(table: DelimitedTable, index: list[str], spec: ClipSpec) -> np.ndarray:
    """Frame number of every data row, ``(N,) int64``, by the sidecar's ``frame_from``."""
    frame_from = spec.frame_from or "index"
    if frame_from == "row":
        return np.arange(table.n_rows, dtype=np.int64)
    if frame_from == "image_name":
        return _image_numbers(table, index)
    row = _first_image(table, index)
    if row is not None:
        shown = "\\".join(table.columns[name][row].as_py() for name in index)
        raise table.error(row, "frame", f"{quoted(shown)} is an image path (DeepLabCut "
                          'labelled data); add "frame_from": "row" to '
                          f"{Path(spec.path).name} to read the images as independent "
                          'frames, or "frame_from": "image_name" to place them in their '
                          "video by the image's number")
    return table.frames(index[0])


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a DeepLabCut CSV file.

    Every (data row, body part) of the chosen individual becomes a row, its confidence
    the likelihood (NaN without a likelihood column, as in labelled data).

    Raises
    ------
    InputError
        Naming the line and the ``bodypart.coord`` column of the first bad cell, the
        header row at fault, or the sidecar key (``individual``, ``frame_from``) to give.
    """
    path = Path(path)
    data = read_bytes(path)
    lines = TextLines.of(data)
    layout = _header(path, data, lines)
    chosen = _individual_columns(path, layout, spec) & _named_columns(layout)
    columns = _columns(path, layout, chosen)
    bodyparts = list(dict.fromkeys(bodypart for bodypart, _ in columns))
    bodyparts_line = layout.rows["bodyparts"][0]
    joints = resolve_names(bodyparts, spec, skeleton, path,
                           lambda k: (bodyparts_line, "bodyparts"))
    index = ["frame"] + [f"frame.{k}" for k in range(1, layout.index_columns)]
    chosen_names = iter(f"{bodypart}.{coord}" for bodypart, coord in columns)
    names = index + [next(chosen_names) if keep else f"\0{k}" for k, keep in enumerate(chosen)]
    table = read_delimited(path, data, names=names, header_lines=len(layout.rows))
    if not table.n_rows:
        raise InputError(path, "has header rows but no data rows",
                         line=layout.rows["coords"][0])
    frame = _frames(table, index, spec)
    # Labelled images read in row order are unrelated frames (picked from a video, often
    # from several): no stage may treat them as a track.
    images = spec.frame_from == "row" and _first_image(table, index) is not None
    kept = [(bodypart, joint) for bodypart, joint in zip(bodyparts, joints, strict=True)
            if joint >= 0]

    def wide(coord: str) -> np.ndarray:
        """``(N, P)``: ``coord`` of every kept body part, NaN where empty or absent."""
        return np.stack([table.numbers(f"{bodypart}.{coord}", allow_empty=True)
                         if (bodypart, coord) in columns else np.full(table.n_rows, np.nan)
                         for bodypart, _ in kept], axis=1)

    x, y, likelihood = wide("x"), wide("y"), wide("likelihood")
    source, files = single_file_rows(path, x.size)
    joint_names = list(skeleton.joints)
    for bodypart, joint in kept:
        joint_names[joint] = bodypart
    return Observations(
        frame=np.repeat(frame, len(kept)),
        joint=np.tile([joint for _, joint in kept], table.n_rows).astype(np.int64),
        u=x.ravel(),
        v=y.ravel(),
        confidence=likelihood.ravel(),
        line=np.repeat(table.line, len(kept)),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
        names=frozenset(bodyparts),
        fields={"u": "{joint}.x", "v": "{joint}.y", "confidence": "{joint}.likelihood"},
        joint_names=tuple(joint_names),
        sampling=IMAGES if images else VIDEO,
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


FORMAT = InputFormat(name="dlc", suffix=".dlc.csv", kind="tracks", read=read, write=write,
                     sidecar_keys=("individual", "frame_from"))
