"""The registry of inbox input formats, recognised by file name.

Every input file in the inbox is named ``<clip_id><suffix>``: the suffix says which
format it is (``.tracks.csv``, ``.openpose`` for a folder, ...). Each format is an
:class:`InputFormat` with a *kind*:

``tracks``
    2D keypoint tracks of one clip; every clip has exactly one track or marker file.
``markers``
    3D marker tracks of one clip (its data file instead of 2D tracks).
``truth``
    Optional 3D ground truth of one clip.
anything else
    Inputs that belong to other readers (``xray``, ``markers``): the inbox scan hands
    them over untouched, grouped by format name.

The formats are registered in one place, :mod:`handdb.ingest`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from handdb.errors import RegistryError
from handdb.registry import Registry

#: The suffix of a clip's sidecar, ``<clip_id>.clip.json``.
SIDECAR_SUFFIX = ".clip.json"

#: Kind of the 3D marker formats: a clip's data file that is already 3D.
MARKERS_KIND = "markers"

#: Kinds a clip's one data file may be: 2D tracks or 3D markers.
DATA_KINDS = ("tracks", MARKERS_KIND)

#: Kinds of input the inbox scan assembles into clips.
CLIP_KINDS = (*DATA_KINDS, "truth")


@dataclass(frozen=True)
class InputFormat:
    """One input format of the inbox.

    Attributes
    ----------
    name
        Short name, e.g. ``"openpose"``; it is the ``source_format`` of clips read with it.
    suffix
        File-name suffix that identifies the format, e.g. ``".dlc.csv"``.
    kind
        ``"tracks"``, ``"truth"`` or the kind of another reader (``"xray"``, ...).
    read
        ``read(path, spec, skeleton)``; for ``tracks`` it returns
        :class:`~handdb.ingest.observations.Observations`, for ``truth``
        :class:`~handdb.ingest.observations.Positions`.
    write
        Writes the format from arrays (for the demo and tests), or ``None``.
    directory
        Whether the input is a folder rather than a file.
    read_truth
        For track formats that also carry ground truth (the thesis's Maya export):
        ``read_truth(path, spec, skeleton) -> Positions``; ``None`` otherwise.
    sidecar_keys
        The reader options of the sidecar (:data:`handdb.ingest.sidecar.READER_KEYS`) this
        format reads; a sidecar giving another is refused.
    members
        For a folder format, ``members(folder) -> [path]``: the files of the folder its
        reader reads, which are all the clip's content hash covers (a video beside the
        keypoint files is neither read nor hashed); ``None``: every visible file
        (:func:`~handdb.ingest.limits.folder_files`).
    """

    name: str
    suffix: str
    kind: str
    read: Callable[..., Any]
    write: Callable[..., Any] | None = None
    directory: bool = False
    read_truth: Callable[..., Any] | None = None
    sidecar_keys: tuple[str, ...] = ()
    members: Callable[[Path], list[Path]] | None = None


#: Every input format by name, filled in :mod:`handdb.ingest`.
FORMATS: Registry[InputFormat] = Registry("input format")


def register_format(fmt: InputFormat) -> InputFormat:
    """Add ``fmt`` to :data:`FORMATS` and return it.

    Raises
    ------
    RegistryError
        If its name or its suffix is taken, or its suffix is the sidecar's.
    """
    if fmt.suffix == SIDECAR_SUFFIX:
        raise RegistryError(f"'{SIDECAR_SUFFIX}' is the sidecar suffix, not a data format")
    for other in FORMATS.values():
        if fmt.suffix == other.suffix:
            raise RegistryError(f"input format '{fmt.name}' ({fmt.suffix}) clashes with "
                                f"registered format '{other.name}' ({other.suffix})")
    return FORMATS.add(fmt.name, fmt)


def registered_formats() -> tuple[InputFormat, ...]:
    """Every registered format, longest suffix first (the order names are matched in)."""
    return tuple(sorted(FORMATS.values(), key=lambda f: (-len(f.suffix), f.name)))


def get_format(name: str) -> InputFormat:
    """Return the registered format called ``name`` (:class:`UnknownNameError` if none)."""
    return FORMATS[name]


def match_format(path: Path) -> tuple[InputFormat, str] | None:
    """Return the format of inbox entry ``path`` and the clip id its name carries.

    ``None`` when no registered format claims the name (the entry is not an input), or
    when the entry is a file where the format wants a folder or the reverse.
    """
    for fmt in registered_formats():
        if path.name.endswith(fmt.suffix) and len(path.name) > len(fmt.suffix):
            if path.is_dir() != fmt.directory:
                return None
            return fmt, path.name[: -len(fmt.suffix)]
    return None
