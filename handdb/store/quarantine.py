"""The ``quarantine`` table: every input the build refused, with where and why."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

import pyarrow as pa

from handdb.errors import HanddbError, InputError
from handdb.ingest.inbox import inbox_relative
from handdb.store import tables

_KEY_COLUMNS = ("file", "line", "field", "stage", "reason", "content_hash")


@dataclass(frozen=True)
class Refusal:
    """An input the build refused: the file, where in it, and why."""

    file: str
    reason: str
    error_type: str
    line: int | None = None
    field: str | None = None
    clip_id: str | None = None
    stage: str | None = None

    @classmethod
    def from_error(
        cls, error: HanddbError, *, file: str | None = None, clip_id: str | None = None
    ) -> Refusal:
        """Describe ``error``; ``file`` and ``clip_id`` apply when the error names none."""
        if isinstance(error, InputError):
            return cls(file=error.file, reason=error.reason, error_type=type(error).__name__,
                       line=error.line, field=error.field, clip_id=error.clip_id or clip_id)
        return cls(file=file or "", reason=str(error), error_type=type(error).__name__,
                   clip_id=clip_id)

    def __str__(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        what = f" field '{self.field}':" if self.field else ""
        return f"{where}:{what} {self.reason}"


def _content_hash(file: str) -> str | None:
    path = Path(file)
    if not path.is_file():
        return None
    return hashlib.sha256(path.read_bytes()).hexdigest()


def quarantine_table(
    refusals: list[Refusal], inbox: str | Path, previous: pa.Table, now: datetime | None = None
) -> pa.Table:
    """Rows for ``refusals``, keeping the time of rows already in ``previous``.

    A refusal already recorded for the same file content keeps its first time, so a build
    that refuses nothing new leaves the table unchanged.
    """
    inbox = Path(inbox)
    now = now or datetime.now(UTC)
    seen = {tuple(row[k] for k in _KEY_COLUMNS): row["time"] for row in previous.to_pylist()}
    rows = []
    for refusal in refusals:
        row = {
            "file": inbox_relative(refusal.file, inbox),
            "line": refusal.line,
            "field": refusal.field,
            "stage": refusal.stage,
            "reason": refusal.reason,
            "error_type": refusal.error_type,
            "clip_id": refusal.clip_id,
            "content_hash": _content_hash(refusal.file),
        }
        row["time"] = seen.get(tuple(row[k] for k in _KEY_COLUMNS), now)
        rows.append(row)
    if not rows:
        return tables.empty("quarantine")
    return tables.from_columns("quarantine", {k: [r[k] for r in rows] for k in rows[0]})
