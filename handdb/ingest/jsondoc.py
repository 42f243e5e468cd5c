"""Loading JSON input files with errors that say where they went wrong."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from handdb.errors import InputError


def load_json(path: Path) -> Any:
    """Parse ``path`` as JSON.

    Raises
    ------
    InputError
        For an empty file, text that is not UTF-8, or a syntax error (with its line; a
        truncated file fails at its last line).
    """
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"is not UTF-8 text ({exc.reason})") from None
    if not text.strip():
        raise InputError(path, "is empty")
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        truncated = exc.pos >= len(text.rstrip())
        raise InputError(path, f"is not valid JSON: {exc.msg}"
                         + ("; the file looks truncated" if truncated else ""),
                         line=exc.lineno) from None


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
        raise InputError(path, f"must be a list of numbers, got {_preview(value)}", field=field)
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


def _preview(value: Any) -> str:
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def finite_number(value: Any, path: Path, field: str) -> float:
    """``value`` as a finite float, or an :class:`InputError` naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(path, f"must be a finite number, got {_preview(value)}", field=field)
    return float(value)
