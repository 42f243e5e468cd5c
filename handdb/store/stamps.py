"""Digests a build need not compute again: files known unchanged from their stat alone.

A build hashes every clip's inbox files (the stage keys) and every stored file of every
clip it keeps (:meth:`~handdb.store.database.Store.clip_damage`): a gigabyte for 40 clips of
5000 frames, most of a rebuild with nothing to do. A :class:`Hashed` entry keeps a digest
with the stamp (size, modification and change times in nanoseconds, inode) each of its
files had when it was hashed; while every file still has that stamp, the digest stands.

An entry is made only from files *settled* when they were stamped: modified and changed
at least :data:`SETTLED_NS` before. A later write then always shows as a newer time, even on
a file system whose clock ticks coarsely (the race git calls "racily clean"). Files are
stamped before they are read, so an edit during the hash shows too.

The entries of a local database are kept in its folder (:data:`STAMPS_FILE`); a remote
database keeps none, and everything is hashed as before. Damage that changes no stamp (a
disk's bit rot under an unchanged file) is not looked for again once a file is settled.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

#: File of the database folder holding the entries, as JSON.
STAMPS_FILE = ".stamps.json"

#: Version of the digests kept: raise it when what a digest covers or how it is computed
#: changes (an inbox clip's content hash, a stored file's fingerprint), so that entries
#: made before are not taken for today's.
STAMPS_VERSION = 1

#: How long before its stamp a file must have last changed to be settled, nanoseconds:
#: more than the coarsest time step of the file systems a database lives on (FAT's 2 s).
SETTLED_NS = 3 * 10**9

#: ``(bytes, st_mtime_ns, st_ctime_ns, st_ino)`` of a file.
Stamp = tuple[int, int, int, int]


@dataclass(frozen=True)
class Hashed:
    """A digest over ``files`` (absolute paths, in the order they were hashed).

    Attributes
    ----------
    files
        The files the digest covers.
    stamps
        Each file's :data:`Stamp` when it was hashed.
    digest
        The hex digest.
    """

    files: tuple[str, ...]
    stamps: tuple[Stamp, ...]
    digest: str


def stamp(path: str) -> Stamp | None:
    """The :data:`Stamp` of the file at ``path``; ``None`` when it is not a regular file."""
    try:
        info = os.stat(path)
    except OSError:
        return None
    return (info.st_size, info.st_mtime_ns, info.st_ctime_ns, info.st_ino)


def settled(stamps: Sequence[Stamp | None], at_ns: int) -> bool:
    """Whether every file was last modified and changed :data:`SETTLED_NS` before ``at_ns``.

    ``at_ns`` is the ``time.time_ns()`` read before the files were stamped.
    """
    return all(s is not None and max(s[1], s[2]) < at_ns - SETTLED_NS for s in stamps)


def entry_key(files: Sequence[str], scope: str = "") -> str:
    """The key of the entry of a digest over ``files``.

    ``scope`` is anything else the digest depends on (the folder a clip's file names are
    relative to).
    """
    return "\n".join([scope, *files])


def known_digest(entries: Mapping[str, Hashed], files: Sequence[str],
                 scope: str = "") -> str | None:
    """The digest over ``files`` in ``entries``, when no file has changed stamp since."""
    entry = entries.get(entry_key(files, scope))
    if entry is None or entry.files != tuple(files):
        return None
    if any(stamp(file) != recorded for file, recorded in zip(files, entry.stamps, strict=True)):
        return None
    return entry.digest


def entry_if_settled(files: Sequence[str], stamps: Sequence[Stamp | None], digest: str,
                     at_ns: int) -> Hashed | None:
    """The entry of a digest over ``files`` stamped ``stamps`` at ``at_ns``, if settled."""
    if not settled(stamps, at_ns):
        return None
    return Hashed(files=tuple(files), stamps=tuple(s for s in stamps if s is not None),
                  digest=digest)


def load_stamps(path: str) -> dict[str, Hashed]:
    """The entries kept at ``path``; none when the file is missing or does not read.

    The file is only a shortcut: a damaged one, or one written for another
    :data:`STAMPS_VERSION`, costs a build its hashing, nothing else.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            kept = json.load(fh)
        if kept.get("version") != STAMPS_VERSION:
            return {}
        entries = {key: Hashed(files=tuple(value["files"]),
                               stamps=tuple(_as_stamp(s) for s in value["stamps"]),
                               digest=str(value["digest"]))
                   for key, value in kept["entries"].items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}
    return {key: entry for key, entry in entries.items()
            if len(entry.stamps) == len(entry.files)}


def _as_stamp(values: Sequence[int]) -> Stamp:
    size, mtime_ns, ctime_ns, inode = (int(value) for value in values)
    return (size, mtime_ns, ctime_ns, inode)


def save_stamps(path: str, entries: Mapping[str, Hashed]) -> None:
    """Keep ``entries`` at ``path``, written aside and renamed into place."""
    aside = f"{path}.tmp"
    with open(aside, "w", encoding="utf-8") as fh:
        json.dump({"version": STAMPS_VERSION, "entries": {
            key: {"files": list(e.files), "stamps": [list(s) for s in e.stamps],
                  "digest": e.digest} for key, e in sorted(entries.items())}}, fh)
    os.replace(aside, path)
