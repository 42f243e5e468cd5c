"""Vectorised reading of delimited text files with line numbers for every row.

pyarrow parses the file in one pass; the line of each data row is found by numpy over the
raw bytes, so a row that fails a vectorised check can be reported by its 1-based line in
the file without a Python loop over rows. Fields are delimited plainly: a field may be
quoted but may not contain the delimiter or a line break.

A file whose data rows are plain (no quote, no blank line among them, no carriage return
but before a line feed) is first read with the columns a reader names already parsed to
numbers, its lines following the header one for one. Only when that read fails, or finds
a value the checks would refuse, is the file read again as strings, which is what says
where and why it is wrong.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv

from handdb.errors import InputError
from handdb.ingest.limits import frame_limit_reason, quoted, read_input

#: A decimal number: optional sign, digits with an optional fraction, optional exponent.
#: Cells are parsed by pyarrow; the pattern finds the cell that pyarrow refused.
NUMBER_PATTERN = r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$"

#: A whole number written without fraction or exponent.
INTEGER_PATTERN = r"^-?\d+$"

_NEWLINE, _CARRIAGE_RETURN = ord("\n"), ord("\r")

#: The byte-order marks of UTF-16 text.
_UTF16_MARKS = (b"\xff\xfe", b"\xfe\xff")

#: A delimiter no text line holds, to read each line as one cell.
_UNUSED_DELIMITER = "\x1f"

#: The only cell a typed read takes for a missing value: an empty one.
_EMPTY_CELL = [""]


def read_bytes(path: Path) -> bytes:
    """Return the bytes of the text file ``path``.

    Raises
    ------
    InputError
        If ``path`` is not a regular file or is too large
        (:func:`~handdb.ingest.limits.read_input`), holds no text, is UTF-16, ends its
        lines with carriage returns alone, or holds a NUL byte.
    """
    data = read_input(path)
    if not data or data.isspace():
        raise InputError(path, "is empty")
    if data.startswith(_UTF16_MARKS):
        raise InputError(path, "is UTF-16 text; save it as UTF-8")
    if b"\n" not in data and data.count(b"\r") > 1:
        raise InputError(path, "uses carriage returns alone as line ends (old Mac text); "
                         "save it with LF or CRLF line ends")
    nul = data.find(b"\0")
    if nul >= 0:
        raise InputError(path, "holds a NUL byte; the file is binary or damaged",
                         line=data.count(b"\n", 0, nul) + 1)
    return data


@dataclass(frozen=True)
class TextLines:
    """Byte spans of the lines of a text, ``(L,) int64`` offsets each."""

    start: np.ndarray
    end: np.ndarray

    @classmethod
    def of(cls, data: bytes) -> TextLines:
        """Split ``data`` into lines; a carriage return before a line feed is dropped."""
        buf = np.frombuffer(data, dtype=np.uint8)
        breaks = np.flatnonzero(buf == _NEWLINE)
        start = np.concatenate([[0], breaks + 1])
        end = np.concatenate([breaks, [buf.size]])
        if buf.size and buf[-1] == _NEWLINE:
            start, end = start[:-1], end[:-1]
        has_cr = (end > start) & (buf[np.maximum(end - 1, 0)] == _CARRIAGE_RETURN)
        return cls(start=start, end=end - has_cr)

    @staticmethod
    def leading(data: bytes, count: int) -> list[tuple[int, int, int]]:
        """The first ``count`` non-blank lines of ``data``, as :meth:`of` splits it.

        Found without splitting the whole text: for a file's header.

        Returns
        -------
        list of (int, int, int)
            Each line's 1-based number and byte span (start, end); fewer than ``count``
            when ``data`` holds fewer.
        """
        found: list[tuple[int, int, int]] = []
        number, start = 0, 0
        while len(found) < count and start < len(data):
            stop = data.find(b"\n", start)
            stop = len(data) if stop < 0 else stop
            number += 1
            end = stop - (stop > start and data[stop - 1] == _CARRIAGE_RETURN)
            if end > start:
                found.append((number, start, end))
            start = stop + 1
        return found

    @property
    def nonblank(self) -> np.ndarray:
        """1-based numbers of the lines that are not empty, ``(K,) int64``."""
        return np.flatnonzero(self.end > self.start) + 1

    def count(self, data: bytes, byte: str) -> np.ndarray:
        """How often ``byte`` occurs on each line, ``(L,) int64``."""
        hits = np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == ord(byte))
        line = np.searchsorted(self.start, hits, side="right") - 1
        return np.bincount(line, minlength=self.start.size)


@dataclass(frozen=True)
class DelimitedTable:
    """The data rows of a delimited file as strings, with their line numbers.

    Attributes
    ----------
    path
        The file.
    columns
        Column name -> the cells: a ``pyarrow.StringArray``, whitespace trimmed, or the
        values already parsed (``int64``, ``float64``, null for an empty cell) when the
        file was read typed (:func:`read_delimited`'s ``types``).
    line
        ``(N,) int64``, 1-based line of each row in the file.
    """

    path: Path
    columns: dict[str, pa.Array]
    line: np.ndarray

    @property
    def n_rows(self) -> int:
        """Number of data rows."""
        return int(self.line.size)

    def take(self, keep: np.ndarray) -> DelimitedTable:
        """The rows where ``keep`` (``(N,) bool``) is true, as a new table."""
        mask = pa.array(keep)
        return DelimitedTable(path=self.path, line=self.line[keep],
                              columns={name: cells.filter(mask)
                                       for name, cells in self.columns.items()})

    def error(self, row: int, column: str, reason: str) -> InputError:
        """Return an :class:`InputError` at data row ``row``, column ``column``."""
        return InputError(self.path, reason, line=int(self.line[row]), field=column)

    def _first_mismatch(self, column: str, pattern: str, skip_empty: bool) -> int:
        """Row of the first cell of ``column`` not matching ``pattern``."""
        cells = self.columns[column]
        fine = pc.match_substring_regex(cells, pattern)
        if skip_empty:
            fine = pc.or_(fine, pc.equal(cells, ""))
        bad = np.flatnonzero(~fine.to_numpy(zero_copy_only=False))
        if not bad.size:
            raise self.error(0, column, "holds a value that cannot be parsed")
        return int(bad[0])

    def numbers(self, column: str, *, allow_empty: bool) -> np.ndarray:
        """Parse ``column`` as decimal numbers, ``(N,) float64`` with NaN for empty cells.

        Raises
        ------
        InputError
            At the first cell that is not a number (NaN and infinity included), or at the
            first empty cell when ``allow_empty`` is false.
        """
        cells = self.columns[column]
        if pa.types.is_floating(cells.type):
            values = cells.to_numpy(zero_copy_only=False)
            is_empty = cells.is_null().to_numpy(zero_copy_only=False)
        else:
            values, is_empty = self._parse_numbers(column)
        if not allow_empty and is_empty.any():
            row = int(np.flatnonzero(is_empty)[0])
            raise self.error(row, column, "is empty; a value is required")
        return values

    def _parse_numbers(self, column: str) -> tuple[np.ndarray, np.ndarray]:
        """The string cells of ``column`` as ``(N,) float64`` and ``(N,) bool`` empty.

        Raises
        ------
        InputError
            At the first cell that is not a finite number.
        """
        cells = self.columns[column]
        empty = pc.equal(cells, "")
        try:
            values = pc.cast(pc.if_else(empty, None, cells), pa.float64())
        except pa.ArrowInvalid:
            row = self._first_mismatch(column, NUMBER_PATTERN, skip_empty=True)
            raise self.error(row, column, f"{quoted(cells[row].as_py())} is not a number"
                             ) from None
        values = values.to_numpy(zero_copy_only=False)
        is_empty = empty.to_numpy(zero_copy_only=False)
        non_finite = np.flatnonzero(~np.isfinite(values) & ~is_empty)
        if non_finite.size:
            row = int(non_finite[0])
            raise self.error(row, column, f"{quoted(cells[row].as_py())} is not a finite "
                             "number; leave the cell empty for a missing point")
        return values, is_empty

    def frames(self, column: str) -> np.ndarray:
        """Parse ``column`` as frame numbers (whole, from 0), ``(N,) int64``.

        Frame numbers beyond :data:`~handdb.ingest.limits.MAX_FRAMES` are refused by
        :class:`~handdb.ingest.observations.Observations`; those beyond int64 here.
        """
        cells = self.columns[column]
        try:
            frame = pc.cast(cells, pa.int64()).to_numpy(zero_copy_only=False)
        except pa.ArrowInvalid:
            whole = pc.match_substring_regex(cells, INTEGER_PATTERN).to_numpy(
                zero_copy_only=False)
            if whole.all():
                row = int(np.argmax(pc.utf8_length(cells).to_numpy(zero_copy_only=False)))
                raise self.error(row, column, frame_limit_reason(cells[row].as_py())) from None
            row = int(np.argmin(whole))
            raise self.error(row, column, f"{quoted(cells[row].as_py())} is not a whole frame "
                             "number; frames count 0, 1, 2, ...") from None
        negative = np.flatnonzero(frame < 0)
        if negative.size:
            row = int(negative[0])
            raise self.error(row, column, f"frame {frame[row]} is negative; frames count "
                             "from 0")
        return frame

    def dictionary(self, column: str) -> tuple[list[str], np.ndarray]:
        """Distinct values of ``column`` and, per row, the index of its value."""
        encoded = self.columns[column].dictionary_encode()
        codes = encoded.indices.to_numpy(zero_copy_only=False).astype(np.int64)
        return encoded.dictionary.to_pylist(), codes


#: Field separators that spreadsheets write in "CSV" files for locales whose decimal mark
#: is a comma, by name, for the refusal of a file that uses one of them.
FOREIGN_SEPARATORS = {";": "semicolons", "\t": "tabs"}

#: The prefix of the placeholder name given to a column whose header cell is empty.
UNNAMED_PREFIX = "\0unnamed"


def split_header(line: bytes, delimiter: str) -> list[str]:
    """Cells of one header line, trimmed and unquoted (a leading byte-order mark dropped)."""
    text = line.decode("utf-8-sig", errors="replace").strip()
    return [cell.strip().strip('"').strip() for cell in text.split(delimiter)]


def check_separator(path: Path, cells: list[str], line: int, delimiter: str = ",") -> None:
    """Refuse a header line that is one cell holding another separator than ``delimiter``.

    Parameters
    ----------
    path
        The file, for the message.
    cells
        The header line's cells, split at ``delimiter`` (:func:`split_header`).
    line
        Its 1-based line number.
    delimiter
        The separator the format uses.

    Raises
    ------
    InputError
        If the line holds no ``delimiter`` but semicolons or tabs: a spreadsheet saved the
        file with the separators of a locale that writes decimals with commas.
    """
    if len(cells) != 1:
        return
    for separator, name in FOREIGN_SEPARATORS.items():
        if separator in cells[0]:
            raise InputError(path, f"separates its fields with {name}, not '{delimiter}' (a "
                             "spreadsheet's CSV for a locale with decimal commas); save it "
                             f"with '{delimiter}' between fields and '.' in decimals",
                             line=line, field=cells[0].split(separator)[0])


def unnamed_placeholders(names: list[str]) -> list[str]:
    """``names`` with every empty one replaced by a placeholder no header can hold.

    A column without a name (the index column pandas writes, the empty columns a
    spreadsheet leaves after the last) is read under :data:`UNNAMED_PREFIX` ``<k>`` and
    never looked at.
    """
    return [name or f"{UNNAMED_PREFIX}{k}" for k, name in enumerate(names)]


def _has_empty(cells: pa.Array) -> bool:
    """Whether a cell of ``cells`` (strings or parsed values) is empty.

    pyarrow reads a blank line as a row of empty cells, where the string read skips it: a
    typed read whose first column has an empty cell may hold one.
    """
    if cells.null_count:
        return True
    return pa.types.is_string(cells.type) and bool(pc.any(pc.equal(cells, "")).as_py())


def _read_plain(path: Path, data: bytes, *, names: list[str], header_lines: int,
                delimiter: str, types: Mapping[str, pa.DataType]) -> DelimitedTable | None:
    """:func:`read_delimited` in one typed pass, for a file whose data rows are plain.

    ``None`` when the file may not be plain (a quote, a carriage return but before a line
    feed, an empty cell in the first column, which a blank line gives, no line after the
    header), when pyarrow refuses a cell, or when a parsed value is one the checks refuse
    (an empty frame, a number that is not finite): the string read then says where and
    why. A plain file's rows are its lines after the header, one for one.
    """
    if b'"' in data or (b"\r" in data and data.count(b"\r") != data.count(b"\r\n")):
        return None
    last_line, first_data = 0, 0
    if header_lines:
        header = TextLines.leading(data, header_lines)
        if len(header) < header_lines:
            return None
        last_line, _, end = header[-1]
        first_data = data.find(b"\n", end) + 1
        if not 0 < first_data < len(data):
            return None
    try:
        table = pacsv.read_csv(
            pa.BufferReader(pa.py_buffer(data).slice(first_data)),
            read_options=pacsv.ReadOptions(column_names=names),
            parse_options=pacsv.ParseOptions(delimiter=delimiter, quote_char=False,
                                             ignore_empty_lines=False),
            convert_options=pacsv.ConvertOptions(
                column_types={name: types.get(name, pa.string()) for name in names},
                null_values=_EMPTY_CELL, strings_can_be_null=False),
        )
    except pa.ArrowInvalid:
        return None
    columns = {}
    for name in names:
        cells = table.column(name).combine_chunks()
        if pa.types.is_string(cells.type):
            cells = pc.utf8_trim_whitespace(cells)
        elif pa.types.is_integer(cells.type) and cells.null_count:
            return None
        elif pa.types.is_floating(cells.type) and (
                np.count_nonzero(~np.isfinite(cells.to_numpy(zero_copy_only=False)))
                != cells.null_count):
            return None
        columns[name] = cells
    if _has_empty(columns[names[0]]):
        return None
    line = np.arange(last_line + 1, last_line + 1 + table.num_rows, dtype=np.int64)
    return DelimitedTable(path=path, columns=columns, line=line)


def read_delimited(path: Path, data: bytes, *, names: list[str], header_lines: int,
                   delimiter: str = ",", types: Mapping[str, pa.DataType] | None = None
                   ) -> DelimitedTable:
    """Parse the data rows of ``data`` (the bytes of ``path``).

    Parameters
    ----------
    path
        The file, for messages.
    data
        Its bytes.
    names
        A name for each column; every data row must have exactly ``len(names)`` cells.
    header_lines
        Number of non-blank lines before the first data row.
    delimiter
        The single-character field delimiter.
    types
        Columns to parse while reading (``pa.int64()``, ``pa.float64()``), when every
        cell of the file parses; they are read as strings otherwise, as the other
        columns are, and :meth:`DelimitedTable.numbers` and :meth:`~DelimitedTable.frames`
        parse them, naming the first bad cell.

    Raises
    ------
    InputError
        At the first row with too few or too many cells (a truncated file), or for
        text that is not UTF-8.
    """
    plain = _read_plain(path, data, names=names, header_lines=header_lines,
                        delimiter=delimiter, types=types or {})
    if plain is not None:
        return plain
    return read_strings(path, data, names=names, header_lines=header_lines,
                        delimiter=delimiter)


def read_strings(path: Path, data: bytes, *, names: list[str], header_lines: int,
                 delimiter: str = ",") -> DelimitedTable:
    """:func:`read_delimited` of any file, every column as strings, lines found by numpy.

    Raises
    ------
    InputError
        As :func:`read_delimited` does.
    """
    lines = TextLines.of(data)
    nonblank = lines.nonblank
    data_lines = nonblank[header_lines:]
    cells = lines.count(data, delimiter)[data_lines - 1] + 1
    wrong = np.flatnonzero(cells != len(names))
    if wrong.size:
        row = int(wrong[0])
        line = int(data_lines[row])
        text = data[lines.start[line - 1]:lines.end[line - 1]]
        hint = ("; the file looks truncated" if row == data_lines.size - 1 else "")
        if cells[row] > len(names) and b'"' in text:
            hint = (f"; a quoted cell holds a '{delimiter}' (a decimal comma?): use '.' for "
                    "decimals")
        shown = delimiter.join(names)
        raise InputError(
            path, f"has {cells[row]} fields, expected {len(names)} "
            f"({shown if len(shown) <= 80 else shown[:77] + '...'}){hint}", line=line)
    if not data_lines.size:
        empty = pa.array([], pa.string())
        return DelimitedTable(path=path, columns=dict.fromkeys(names, empty),
                              line=data_lines.astype(np.int64))
    first_data = int(lines.start[data_lines[0] - 1])
    try:
        table = pacsv.read_csv(
            pa.BufferReader(pa.py_buffer(data).slice(first_data)),
            read_options=pacsv.ReadOptions(column_names=names),
            parse_options=pacsv.ParseOptions(delimiter=delimiter),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(names, pa.string()),
                strings_can_be_null=False, quoted_strings_can_be_null=False),
        )
    except pa.ArrowInvalid as exc:
        raise InputError(path, f"cannot be parsed: {exc}") from None
    columns = {name: pc.utf8_trim_whitespace(table.column(name).combine_chunks())
               for name in names}
    return DelimitedTable(path=path, columns=columns, line=data_lines.astype(np.int64))


def read_whitespace_separated(path: Path, data: bytes, *, names: list[str]) -> DelimitedTable:
    """Parse ``data`` (the bytes of ``path``) as fields separated by runs of blanks.

    Blank lines and blanks at the ends of lines are ignored; every other line must have
    exactly ``len(names)`` fields.

    Raises
    ------
    InputError
        At the first line with too few or too many fields (a truncated file), or for
        text that is not UTF-8.
    """
    try:
        table = pacsv.read_csv(
            pa.BufferReader(pa.py_buffer(data)),
            read_options=pacsv.ReadOptions(column_names=["text"]),
            parse_options=pacsv.ParseOptions(delimiter=_UNUSED_DELIMITER, quote_char=False),
            convert_options=pacsv.ConvertOptions(column_types={"text": pa.string()},
                                                 strings_can_be_null=False),
        )
    except pa.ArrowInvalid as exc:
        raise InputError(path, f"cannot be parsed: {exc}") from None
    text = pc.utf8_trim_whitespace(table.column("text").combine_chunks())
    filled = pc.not_equal(text, "")
    text = text.filter(filled)
    line = TextLines.of(data).nonblank[filled.to_numpy(zero_copy_only=False)]
    fields = pc.ascii_split_whitespace(text)
    counts = pc.list_value_length(fields).to_numpy(zero_copy_only=False)
    wrong = np.flatnonzero(counts != len(names))
    if wrong.size:
        row = int(wrong[0])
        raise InputError(
            path, f"has {counts[row]} fields, expected {len(names)} ({' '.join(names)})"
            + ("; the file looks truncated" if row == counts.size - 1 else ""),
            line=int(line[row]))
    columns = {name: pc.list_element(fields, k) for k, name in enumerate(names)}
    return DelimitedTable(path=path, columns=columns, line=line.astype(np.int64))


def write_csv(path: str | Path, columns: dict[str, pa.Array],
              header: list[list[str]] | None = None, delimiter: str = ",") -> None:
    """Write ``columns`` as plain delimited text with empty cells for nulls.

    ``header`` gives the header rows (default: one row of the column names; ``[]`` for
    none).
    """
    rows = [list(columns)] if header is None else header
    with Path(path).open("wb") as fh:
        fh.write("".join(delimiter.join(row) + "\n" for row in rows).encode())
        pacsv.write_csv(pa.table(columns), fh, write_options=pacsv.WriteOptions(
            include_header=False, quoting_style="none", delimiter=delimiter))
