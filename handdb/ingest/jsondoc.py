"""Loading JSON input files with errors that say where they went wrong.

Every JSON document handdb reads, sidecars included, goes through :func:`parse_json`:
it refuses nesting deeper than :data:`~handdb.ingest.limits.MAX_JSON_DEPTH` before the
parser recurses, integer literals too long to be a count or an id, and keys given twice
in one object (JSON leaves the meaning of a repeated key open; Python keeps the last).
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from handdb.errors import InputError
from handdb.ingest.limits import MAX_FILE_BYTES, MAX_JSON_DEPTH, MAX_JSON_INTEGER_DIGITS, read_input

#: A JSON string literal, escapes included.
_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)

#: The byte-order marks of UTF-16 text.
_UTF16_MARKS = (b"\xff\xfe", b"\xfe\xff")


class _RefusedLiteral(ValueError):
    """Raised from the parser's hooks; carries the reason and the literal to locate."""

    def __init__(self, reason: str, literal: str | None = None, field: str | None = None):
        super().__init__(reason)
        self.reason, self.literal, self.field = reason, literal, field


def _integer(literal: str) -> int:
    digits = len(literal.lstrip("-"))
    if digits > MAX_JSON_INTEGER_DIGITS:
        raise _RefusedLiteral(f"holds an integer of {digits} digits; no value handdb reads "
                              f"has more than {MAX_JSON_INTEGER_DIGITS}", literal)
    return int(literal)


def _object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    doc = dict(pairs)
    if len(doc) < len(pairs):
        counts = Counter(key for key, _ in pairs)
        twice = next(key for key, _ in pairs if counts[key] > 1)
        raise _RefusedLiteral("is given twice in one object; keep one of them", field=twice)
    return doc


def _line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, max(offset, 0)) + 1


def _check_depth(text: str, path: Path) -> None:
    """Refuse ``text`` if its arrays and objects nest deeper than :data:`MAX_JSON_DEPTH`."""
    if text.count("[") + text.count("{") <= MAX_JSON_DEPTH:
        return
    bare = np.frombuffer(_STRING.sub('""', text).encode("utf-8", "replace"), dtype=np.uint8)
    step = (np.isin(bare, (ord("["), ord("{"))).astype(np.int32)
            - np.isin(bare, (ord("]"), ord("}"))).astype(np.int32))
    depth = np.cumsum(step, dtype=np.int64)
    deepest = int(depth.max(initial=0))
    if deepest > MAX_JSON_DEPTH:
        first = int(np.argmax(depth > MAX_JSON_DEPTH))
        line = int(np.count_nonzero(bare[:first] == ord("\n"))) + 1
        raise InputError(path, f"nests JSON {deepest} levels deep (limit {MAX_JSON_DEPTH}); "
                         "this is not a file a tool writes", line=line)


def parse_json(text: str, path: Path) -> Any:
    """Parse ``text``, the content of ``path``, as JSON within handdb's limits.

    Raises
    ------
    InputError
        For a syntax error (with its line; a truncated file fails at its last line),
        nesting deeper than :data:`MAX_JSON_DEPTH`, an integer literal of more than
        :data:`MAX_JSON_INTEGER_DIGITS` digits, or a key given twice in one object.
    """
    _check_depth(text, path)
    try:
        return json.loads(text, parse_int=_integer, object_pairs_hook=_object)
    except json.JSONDecodeError as exc:
        truncated = exc.pos >= len(text.rstrip())
        raise InputError(path, f"is not valid JSON: {exc.msg}"
                         + ("; the file looks truncated" if truncated else ""),
                         line=exc.lineno) from None
    except _RefusedLiteral as exc:
        line = _line_of(text, text.find(exc.literal)) if exc.literal else None
        raise InputError(path, exc.reason, line=line, field=exc.field) from None


def load_json(path: Path, max_bytes: int = MAX_FILE_BYTES) -> Any:
    """Parse the file ``path`` as JSON (UTF-8, a byte-order mark allowed).

    Raises
    ------
    InputError
        For a file that is not a regular file or is larger than ``max_bytes``, an empty
        file, text that is not UTF-8, or what :func:`parse_json` refuses.
    """
    data = read_input(path, max_bytes)
    if data.startswith(_UTF16_MARKS):
        raise InputError(path, "is UTF-16 text; save it as UTF-8")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"is not UTF-8 text ({exc.reason})") from None
    if not text.strip():
        raise InputError(path, "is empty")
    return parse_json(text, path)


def number_array(value: Any, path: Path, field: str, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` (nested JSON lists) as a finite ``float64`` array of ``shape``.

    A ``-1`` in ``shape`` accepts any length on that axis.

    Raises
    ------
    InputError
        Naming ``field`` if ``value`` is not numbers, has another shape, or holds NaN or
        infinity.
    """
    if not isinstance(value, list) or _holds_non_number(value):
        raise InputError(path, f"must be a list of numbers, got {preview(value)}", field=field)
    try:
        array = np.array(value, dtype=np.float64)
    except ValueError:
        raise InputError(path, "rows must have equal lengths", field=field) from None
    wanted = tuple(a if s == -1 else s for a, s in zip(array.shape, shape, strict=False))
    if array.ndim != len(shape) or array.shape != wanted:
        expected = " x ".join("N" if s == -1 else str(s) for s in shape)
        raise InputError(path, f"has shape {' x '.join(map(str, array.shape))}, expected "
                         f"{expected}", field=field)
    if not np.isfinite(array).all():
        raise InputError(path, "holds NaN or infinity; numbers must be finite", field=field)
    return array


def _holds_non_number(value: Any) -> bool:
    if isinstance(value, list):
        return any(_holds_non_number(v) for v in value)
    return isinstance(value, bool) or not isinstance(value, int | float)


def preview(value: Any) -> str:
    """``value`` as JSON for a message, cut to 60 characters."""
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def finite_number(value: Any, path: Path, field: str) -> float:
    """``value`` as a finite float, or an :class:`InputError` naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(path, f"must be a finite number, got {preview(value)}", field=field)
    return float(value)
