"""Exception types raised by handdb.

Every error a user can cause with bad input is an :class:`InputError` that names the
file, the line (1-based, where the format has lines) and the field at fault, so that the
message alone says what to fix. The build turns these into ``quarantine`` rows.
"""

from __future__ import annotations

from pathlib import Path


class HanddbError(Exception):
    """Base class of every error handdb raises on purpose."""


class InputError(HanddbError):
    """Input that handdb refuses, located as precisely as the format allows.

    Parameters
    ----------
    file
        The file at fault.
    reason
        What is wrong, phrased so the user knows what to change.
    line
        1-based line number in ``file``, or ``None`` for formats without lines
        (a JSON document, a binary file) or for whole-file problems.
    field
        The column, key or parameter at fault, or ``None``.
    clip_id
        The clip the file belongs to, when known.
    """

    def __init__(
        self,
        file: str | Path,
        reason: str,
        *,
        line: int | None = None,
        field: str | None = None,
        clip_id: str | None = None,
    ) -> None:
        self.file = str(file)
        self.reason = reason
        self.line = line
        self.field = field
        self.clip_id = clip_id
        super().__init__(self._format())

    def _format(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        what = f" field '{self.field}':" if self.field else ""
        return f"{where}:{what} {self.reason}"


class UnknownNameError(HanddbError, ValueError):
    """A name (a method, a format, a skeleton) that no registry knows.

    Parameters
    ----------
    kind
        What the name should have named (``"lifting method"``).
    name
        The name asked for.
    known
        The names that are registered.
    """

    def __init__(self, kind: str, name: str, known: tuple[str, ...]) -> None:
        self.kind = kind
        self.name = name
        self.known = known
        super().__init__(f"unknown {kind} '{name}'; known: {', '.join(known)}")


class ParameterError(HanddbError, ValueError):
    """A method's parameter with a value the method cannot use.

    The parameters come from a sidecar's ``lift`` or ``gap_fill`` object or from the
    command line.
    """


class ClipDataError(HanddbError, ValueError):
    """A clip whose data cannot support a stage: too few points or markers, no frame to start.

    The clip's files are fine as files; the message says what the data lacks.
    """


class GapFillError(ClipDataError):
    """Gap filling cannot complete a clip's tracks from what its data holds.

    The message names the method and what the clip lacks (``auto`` places a joint never
    observed from each frame's observed points, so it needs every frame to observe one),
    and what to do. The build refuses the clip at the gap-filling stage.
    """


class RegistryError(HanddbError):
    """A registry entry added twice under one name."""


class SkeletonError(HanddbError):
    """A skeleton topology that is unknown or inconsistent."""


class SchemaError(HanddbError):
    """A table that does not match its contract in ``schemas/tables``."""


class StoreError(HanddbError):
    """The database folder cannot be read or written as asked."""


class DatabaseLockedError(StoreError):
    """Another build holds the database lock."""


class DatabasePathError(StoreError):
    """A database path that cannot hold a database, or a path inside it handdb will not use.

    A file where the database folder belongs, a folder the build cannot write, or a
    symbolic link inside the database (a write through it would land outside). The
    message names the path and what to change.
    """


class DamagedFileError(StoreError):
    """A file of the database that is there but cannot be read (cut short, overwritten)."""


class DamagedFileWarning(UserWarning):
    """A damaged file of the database left out of a query; the message names the file."""


class QueryError(StoreError):
    """A statement given to query the database that holds no query (empty, only comments)."""


class BoneLengthError(HanddbError):
    """No bone lengths can be had for a clip."""


class StageError(HanddbError):
    """A pipeline stage could not process a clip (the message says why)."""


class MissingToolError(HanddbError):
    """An external program a command needs (Blender for FBX) is not installed."""
