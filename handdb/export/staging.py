"""Export files written aside and renamed into place, so a reader never sees half a file."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged_file(path: Path, prefix: str) -> Iterator[Path]:
    """Yield where to write ``path``'s content; on success, rename it onto ``path``.

    Parameters
    ----------
    path
        The file to write; its folder must exist. An existing file is replaced atomically.
    prefix
        Name prefix of the temporary folder made beside ``path`` (e.g. ``".usd-export-"``),
        so that a left-over folder says which export made it.

    Yields
    ------
    pathlib.Path
        A file of ``path``'s name in a temporary folder on the same file system; the
        folder (with anything else written in it) is removed on exit. When the block
        raises, ``path`` is left as it was.
    """
    with tempfile.TemporaryDirectory(dir=path.parent, prefix=prefix) as folder:
        staged = Path(folder) / path.name
        yield staged
        os.replace(staged, path)
