"""The export formats, by name: what each writes, its file suffixes and what opens it.

Every format is an :class:`ExportFormat` in :data:`FORMATS`, registered in
:mod:`handdb.export` (the package's ``__init__``). An entry names its writer by module and
function, imported only when a file is written, so listing the formats (``handdb export
--help``) or writing a TRC file never imports usd-core, pygltflib or Blender.

A writer is called as ``write(motion, path, options)`` with a
:class:`~handdb.export.stored.StoredMotion`, the output path (its folder exists) and an
:class:`ExportOptions`, and returns the path it wrote. A format whose writer pays a large
start-up per call (FBX starts Blender) also names a batch writer, called as
``write_batch(jobs, out_dir, options)`` with an iterable of ``(motion, path)`` pairs (the
paths in ``out_dir``, which exists); it yields a
:class:`~handdb.export.stored.ClipExport` per file written and, when some clips failed,
raises :class:`~handdb.errors.StageError` naming them after the others are written.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from handdb.errors import ParameterError
from handdb.lazy import LazyFunction
from handdb.registry import Registry


@dataclass(frozen=True)
class ExportOptions:
    """Options a writer may read; each writer's docstring says which it reads.

    Attributes
    ----------
    keep_lengths
        Posed formats: give every bone its stored length (rigid bones, measured
        directions) instead of reproducing ``joints_3d`` exactly.
    at_origin
        Move the clip so its first placed root (wrist) is at the origin horizontally and its
        lowest point on the floor, Y up (:func:`handdb.export.placement.at_origin`);
        ``False`` keeps the camera's coordinates; ``None`` (the default): the format's
        own default, :attr:`ExportFormat.posed` (the animation formats move the hand, TRC
        and C3D keep camera coordinates).
    """

    keep_lengths: bool = False
    at_origin: bool | None = None

    def places_at_origin(self, entry: ExportFormat) -> bool:
        """Whether a file of format ``entry`` is written with the hand at the origin."""
        return entry.posed if self.at_origin is None else self.at_origin


@dataclass(frozen=True)
class ExportFormat:
    """One export format.

    Attributes
    ----------
    name
        What ``handdb export --format`` takes (``"trc"``).
    suffixes
        File suffixes it writes; the first is used when handdb names the file.
    writer
        ``"module:function"`` of the writer (see the module doc).
    description
        What the file holds, one line.
    opens_in
        The tools a user opens it in, one line.
    posed
        ``True`` when the format holds joint rotations, which need every joint of every
        frame placed; ``False`` when missing positions are written as missing.
    batch_writer
        ``"module:function"`` of a writer of many clips at once (see the module doc), or
        ``None`` when clips are written one by one.
    keys_placed_frames
        ``True`` when a posed format keys only the frames that place every joint and holds
        the pose over the others (USD), so a clip with such frames is still written.
    """

    name: str
    suffixes: tuple[str, ...]
    writer: str
    description: str
    opens_in: str
    posed: bool
    batch_writer: str | None = None
    keys_placed_frames: bool = False

    @property
    def suffix(self) -> str:
        """The suffix of files handdb names itself."""
        return self.suffixes[0]

    def load(self) -> Callable[..., Path]:
        """Import and return the writer."""
        return _imported(self.writer)

    def load_batch(self) -> Callable[..., Iterator[Any]] | None:
        """Import and return the batch writer, ``None`` when the format has none."""
        return None if self.batch_writer is None else _imported(self.batch_writer)


def _imported(target: str) -> Any:
    """The function ``target`` (``"module:function"``) names, its module imported now."""
    return LazyFunction(target).function


#: Every export format, registered in :mod:`handdb.export`.
FORMATS: Registry[ExportFormat] = Registry("export format")


def register_format(entry: ExportFormat) -> ExportFormat:
    """Add ``entry`` to :data:`FORMATS` and return it."""
    return FORMATS.add(entry.name, entry)


def format_for_suffix(path: str | Path) -> ExportFormat:
    """The format that writes files ending like ``path``.

    Raises
    ------
    ParameterError
        If no registered format writes that suffix; the message lists those that do.
    """
    suffix = Path(path).suffix.lower()
    for entry in FORMATS.values():
        if suffix in entry.suffixes:
            return entry
    known = ", ".join(s for entry in FORMATS.values() for s in entry.suffixes)
    raise ParameterError(f"{path}: handdb writes no '{suffix}' files; the suffix must be one "
                         f"of {known}")
