"""The export formats, by name: what each writes, its file suffixes and what opens it.

Every format is an :class:`ExportFormat` in :data:`FORMATS`, registered in
:mod:`handdb.export` (the package's ``__init__``). An entry names its writer by module and
function, imported only when a file is written, so listing the formats (``handdb export
--help``) or writing a TRC file never imports usd-core, pygltflib or Blender.

A writer is called as ``write(motion, path, options)`` with a
:class:`~handdb.export.stored.StoredMotion`, the output path (its folder exists) and an
:class:`ExportOptions`, and returns the path it wrote.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from handdb.errors import ParameterError
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
    """

    name: str
    suffixes: tuple[str, ...]
    writer: str
    description: str
    opens_in: str
    posed: bool

    @property
    def suffix(self) -> str:
        """The suffix of files handdb names itself."""
        return self.suffixes[0]

    def load(self) -> Callable[..., Path]:
        """Import and return the writer."""
        module, function = self.writer.split(":")
        writer: Any = getattr(importlib.import_module(module), function)
        return writer


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
