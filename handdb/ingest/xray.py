"""Read phalanx lengths measured on X-ray images (``*.xray.csv``).

A file holds one row per measured segment::

    image_id,finger,segment,length[,subject,sex,age,side]
    1a,index,J1,339.96

``finger`` is one of ``thumb, index, middle, ring, little``; ``segment`` counts the
phalanges from the root of the finger as Chaudhry et al. do: ``J1`` (proximal), ``J2``
(middle; the thumb's distal), ``J3`` (distal; not for the thumb). ``length`` is in any one
unit (pixels of the image, millimetres): only ratios within a finger are used.

Bad input is refused as precisely as possible and the rest goes on. A bad row (bad
number, unknown finger or segment, duplicate) is refused alone; an image whose finger
then lacks a segment, or holds a duplicated or conflicting one, is quarantined for that
finger only, since its ratios would be wrong. A file that cannot be read as such a table
at all (empty, not UTF-8, missing or unknown columns) is refused whole.
"""

from __future__ import annotations

import csv
import math
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa

from handdb.errors import InputError
from handdb.hand.skeletons import FINGERS
from handdb.ingest.registry import InputFormat
from handdb.store import tables

#: The file name suffix the inbox recognises.
XRAY_SUFFIX = ".xray.csv"
#: Longest name an X-ray file may have before its suffix, bytes: the name becomes the
#: key of its partition of ``xray_measurements``, a file name in the store (whose file
#: systems allow 255 bytes, with room left for the store's suffixes).
MAX_XRAY_NAME_BYTES = 128

#: Segments measured on each finger, from its root.
SEGMENTS: dict[str, tuple[str, ...]] = {
    finger: ("J1", "J2") if finger == "thumb" else ("J1", "J2", "J3") for finger in FINGERS
}

REQUIRED_COLUMNS = ("image_id", "finger", "segment", "length")
METADATA_COLUMNS = ("subject", "sex", "age", "side")
SIDES = ("left", "right")


@dataclass(frozen=True)
class _Row:
    line: int
    image_id: str
    finger: str
    segment: str
    length: float
    metadata: dict[str, str | float | None]


def _positive_number(text: str, file: str, line: int, field: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(file, f"must be a number, got {text!r}", line=line,
                         field=field) from None
    if not math.isfinite(value) or value <= 0:
        raise InputError(file, f"must be a finite number greater than 0, got {text!r}",
                         line=line, field=field)
    return value


def _metadata(record: dict[str | None, Any], file: str, line: int) -> dict[str, str | float | None]:
    values: dict[str, str | float | None] = {}
    for column in METADATA_COLUMNS:
        text = (record.get(column) or "").strip()
        if not text:
            values[column] = None
        elif column == "age":
            values[column] = _positive_number(text, file, line, "age")
        elif column == "side":
            if text.lower() not in SIDES:
                raise InputError(file, f"must be left or right, got {text!r}", line=line,
                                 field="side")
            values[column] = text.lower()
        elif column == "sex":
            values[column] = text.lower()
        else:
            values[column] = text
    return values


def _parse_row(record: dict[str | None, Any], file: str, line: int) -> _Row:
    """Parse one CSV record; ``csv.DictReader`` files surplus fields under ``None``."""
    surplus = record.get(None)
    if surplus:
        header = len(record) - 1
        raise InputError(file, f"has {header + len(surplus)} fields; the header has {header}",
                         line=line)
    empty = [c for c in REQUIRED_COLUMNS if not (record[c] or "").strip()]
    if empty:
        raise InputError(file, "is empty", line=line, field=empty[0])
    finger = record["finger"].strip().lower()
    if finger not in SEGMENTS:
        raise InputError(file, f"unknown finger {record['finger']!r}; fingers: "
                         f"{', '.join(FINGERS)}", line=line, field="finger")
    segment = record["segment"].strip().upper()
    if segment not in SEGMENTS[finger]:
        raise InputError(file, f"the {finger} has segments {', '.join(SEGMENTS[finger])}, "
                         f"not {record['segment']!r}", line=line, field="segment")
    return _Row(
        line=line,
        image_id=record["image_id"].strip(),
        finger=finger,
        segment=segment,
        length=_positive_number(record["length"].strip(), file, line, "length"),
        metadata=_metadata(record, file, line),
    )


def _read_records(path: Path) -> list[tuple[int, dict[str | None, Any]]]:
    """Return the non-blank records of the file with their 1-based line numbers."""
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(file, f"is not UTF-8 text ({exc.reason})") from None
    if not text.strip():
        raise InputError(file, "is empty; an X-ray file needs the header "
                         f"{','.join(REQUIRED_COLUMNS)} and one row per measured segment")
    reader = csv.DictReader(text.splitlines())
    header = [c.strip() for c in reader.fieldnames or []]
    reader.fieldnames = header
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise InputError(file, f"the header lacks column '{missing[0]}' (required: "
                         f"{', '.join(REQUIRED_COLUMNS)})", line=1, field=missing[0])
    unknown = [c for c in header if c not in REQUIRED_COLUMNS + METADATA_COLUMNS]
    if unknown:
        raise InputError(file, "unknown column (known: "
                         f"{', '.join(REQUIRED_COLUMNS + METADATA_COLUMNS)})", line=1,
                         field=unknown[0])
    records = [(reader.line_num, record) for record in reader if any(
        (v or "").strip() for v in record.values() if isinstance(v, str))]
    if not records:
        raise InputError(file, "has a header but no measurements", line=1)
    return records


def _complete_groups(rows: list[_Row], refused: dict[tuple[str, str], list[int]],
                     file: str) -> tuple[list[_Row], list[InputError]]:
    """Keep the (image, finger) groups that hold every segment exactly once."""
    groups: dict[tuple[str, str], list[_Row]] = defaultdict(list)
    for row in rows:
        groups[(row.image_id, row.finger)].append(row)
    kept: list[_Row] = []
    errors: list[InputError] = []
    for (image_id, finger), group in groups.items():
        first = group[0].line
        segments = [r.segment for r in group]
        duplicates = sorted({s for s in segments if segments.count(s) > 1})
        missing = [s for s in SEGMENTS[finger] if s not in segments]
        if duplicates:
            lines = [r.line for r in group if r.segment == duplicates[0]]
            errors.append(InputError(
                file, f"image {image_id!r} {finger}: segment {duplicates[0]} is given on "
                f"lines {', '.join(map(str, lines))}; the {finger} of this image is "
                "quarantined until one of them is removed", line=lines[1], field="segment"))
        elif missing:
            why = (f" (refused on line(s) {', '.join(map(str, refused[(image_id, finger)]))})"
                   if (image_id, finger) in refused else "")
            errors.append(InputError(
                file, f"image {image_id!r} {finger}: lacks segment {', '.join(missing)}"
                f"{why}; its ratios need every segment, so the {finger} of this image is "
                "quarantined", line=first, field="segment"))
        else:
            kept.extend(group)
    return kept, errors


def _consistent_images(rows: list[_Row], file: str) -> tuple[list[_Row], list[InputError]]:
    """Quarantine images whose rows disagree on subject, sex, age or side."""
    values: dict[tuple[str, str], set] = defaultdict(set)
    for row in rows:
        for column, value in row.metadata.items():
            if value is not None:
                values[(row.image_id, column)].add(value)
    conflicts = {image_id: column for (image_id, column), seen in values.items()
                 if len(seen) > 1}
    errors = [
        InputError(file, f"image {image_id!r} has conflicting values "
                   f"{sorted(map(str, values[(image_id, column)]))}; the whole image is "
                   "quarantined", line=min(r.line for r in rows if r.image_id == image_id),
                   field=column)
        for image_id, column in conflicts.items()
    ]
    return [r for r in rows if r.image_id not in conflicts], errors


def read_xray(path: str | Path) -> tuple[pa.Table, list[InputError]]:
    """Read an ``*.xray.csv`` file of phalanx lengths.

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    measurements
        Table ``xray_measurements``: one row per segment of every complete
        (image, finger), ``length`` in the file's unit, ``source_file`` the file's name.
    refused
        One :class:`InputError` per refused row and per quarantined (image, finger),
        each naming the file, the 1-based line and the field; or the one error that
        refuses the whole file (not UTF-8, empty, no measurements, or a header lacking
        a required column or naming an unknown one), the table then being empty. Bad
        input never raises, so a caller quarantines what is listed and goes on.
    """
    file = str(path)
    try:
        records = _read_records(Path(path))
    except InputError as error:
        return tables.empty("xray_measurements"), [error]
    rows: list[_Row] = []
    errors: list[InputError] = []
    refused: dict[tuple[str, str], list[int]] = defaultdict(list)
    for line, record in records:
        try:
            rows.append(_parse_row(record, file, line))
        except InputError as exc:
            errors.append(exc)
            finger = (record.get("finger") or "").strip().lower()
            refused[((record.get("image_id") or "").strip(), finger)].append(line)
    rows, group_errors = _complete_groups(rows, refused, file)
    rows, image_errors = _consistent_images(rows, file)
    columns: dict[str, list] = {
        "source_file": [Path(file).name] * len(rows),
        "line": [r.line for r in rows],
        "image_id": [r.image_id for r in rows],
        "finger": [r.finger for r in rows],
        "segment": [r.segment for r in rows],
        "length": [r.length for r in rows],
    }
    for column in METADATA_COLUMNS:
        columns[column] = [r.metadata[column] for r in rows]
    errors = errors + group_errors + image_errors
    return tables.from_columns("xray_measurements", columns), sorted(
        errors, key=lambda e: (e.line or 0, e.field or ""))


#: The inbox format of X-ray measurements; the inbox scan hands these files over by kind.
FORMAT = InputFormat(name="xray", suffix=XRAY_SUFFIX, kind="xray",
                                     read=read_xray)
