"""Limits every reader keeps, and opening an input file safely.

Each bound is checked before anything is allocated from it, so that a hostile or broken
file is refused with a message instead of exhausting memory or hanging the build. The
values come from the real inputs handdb meets: a long capture is hours, not days; a hand
spans centimetres in any unit and at most a few thousand pixels in any image.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import numpy as np

from handdb.errors import InputError

#: The largest number of frames a clip may span: 9.3 h at 30 fps. Dense ``(T, 21)`` float
#: arrays of that length take 170 MB each.
MAX_FRAMES = 1_000_000

#: The largest input file read, in bytes (2 GiB).
MAX_FILE_BYTES = 2 * 1024**3

#: The largest sidecar read, in bytes: a sidecar is a few hundred bytes of settings.
MAX_SIDECAR_BYTES = 1024**2

#: The deepest nesting of JSON arrays and objects accepted; real files nest 4 levels.
MAX_JSON_DEPTH = 64

#: The most digits of an integer literal in JSON; no count, id or frame needs more.
MAX_JSON_INTEGER_DIGITS = 30

#: The highest frame rate accepted, frames per second (high-speed marker systems reach
#: a few thousand).
MAX_FPS = 10_000.0
#: The lowest, frames per second: below it a track is not motion capture.
MIN_FPS = 1.0
#: Relative difference between a file's recorded frame rate and the sidecar's ``fps``
#: taken as equal.
RATE_TOLERANCE = 1e-3

#: The range a bone length given in a sidecar may lie in, metres: finger bones are 1-10 cm,
#: the whole hand about 20; an animated hand may be larger, a number outside this range is
#: a unit or typing mistake.
BONE_LENGTH_RANGE_METRES = (1e-3, 0.5)
#: The range of a sidecar's ``hand_length``, metres.
HAND_LENGTH_RANGE_METRES = (0.03, 1.0)

#: The largest image side accepted, pixels.
MAX_IMAGE_SIDE = 100_000

#: The largest image coordinate accepted, pixels (ten times the largest sensor side).
MAX_PIXEL_COORDINATE = 1e6

#: 2D points all within this magnitude are normalised coordinates (a tool's [0, 1] or
#: [-1, 1] of the image), not pixels: a hand is more than two pixels across.
NORMALISED_BOUND = 1.0

#: The largest 3D coordinate accepted, metres: capture volumes are rooms, not kilometres.
MAX_COORDINATE_METRES = 100.0

#: Clips spanning more frames than this are checked for invented frames.
SPARSE_MIN_SPAN = 1000

#: The smallest share of a clip's frames that must carry a point, once it spans more than
#: :data:`SPARSE_MIN_SPAN` frames: below it the frame numbers are not a clip's
#: (a stray frame 100000 in a 100-frame track, ids of a dataset's global image numbers).
SPARSE_MIN_FILLED = 0.01

#: The longest run of frames without a point a clip may hold, in frames, when it is also
#: longer than all the clip's frames with points: beyond both, the frames after it (or
#: before) are not this clip's (a stray frame 5000 in a 64-frame track), or the clip is
#: mostly invented; either way gap filling would make up the difference.
STRAY_GAP_FRAMES = 30

#: The most characters of a cell or name quoted in a message.
MAX_QUOTED = 40

_FILE_TYPES = {stat.S_ISDIR: "a folder", stat.S_ISFIFO: "a named pipe",
               stat.S_ISCHR: "a character device", stat.S_ISBLK: "a block device",
               stat.S_ISSOCK: "a socket"}


def quoted(text: str) -> str:
    """``text`` in quotes for a message, cut to :data:`MAX_QUOTED` characters."""
    shown = text if len(text) <= MAX_QUOTED else text[:MAX_QUOTED - 3] + "..."
    return repr(shown) if any(c in shown for c in "'\n\r\t\0") else f"'{shown}'"


def file_kind(mode: int) -> str:
    """What a non-regular file of ``st_mode`` ``mode`` is, in words."""
    return next((name for test, name in _FILE_TYPES.items() if test(mode)), "not a file")


def checked_size(path: Path, max_bytes: int = MAX_FILE_BYTES) -> int:
    """Return the size of the regular file ``path`` in bytes, without opening it.

    Raises
    ------
    InputError
        If ``path`` does not exist, is not a regular file (a folder, a named pipe, a
        device such as ``/dev/zero``) or is larger than ``max_bytes``.
    """
    try:
        info = path.stat()
    except FileNotFoundError:
        target = f" to {os.readlink(path)}, which does not exist" if path.is_symlink() else ""
        raise InputError(path, f"cannot be read: it is a symbolic link{target}" if target
                         else "cannot be read: no such file") from None
    if not stat.S_ISREG(info.st_mode):
        raise InputError(path, f"is not a regular file ({file_kind(info.st_mode)}); handdb "
                         "reads inputs from regular files only")
    if info.st_size > max_bytes:
        raise InputError(path, f"is {info.st_size:,} bytes; handdb reads such files up to "
                         f"{max_bytes:,} bytes")
    return info.st_size


def read_input(path: Path, max_bytes: int = MAX_FILE_BYTES) -> bytes:
    """Return the bytes of the regular file ``path``, checked by :func:`checked_size` first.

    Raises
    ------
    InputError
        As :func:`checked_size`.
    """
    checked_size(path, max_bytes)
    return path.read_bytes()


def frame_limit_reason(frame: int | str) -> str:
    """The refusal of a frame number beyond :data:`MAX_FRAMES`."""
    return (f"frame {frame} is beyond handdb's limit of {MAX_FRAMES:,} frames (9.3 h at "
            "30 fps); number frames from the clip's start")


def is_sparse(n_filled: int, n_frames: int) -> bool:
    """Whether a clip of ``n_frames`` with ``n_filled`` frames carrying points is invented.

    True when it spans more than :data:`SPARSE_MIN_SPAN` frames and fewer than
    :data:`SPARSE_MIN_FILLED` of them carry a point.
    """
    return n_frames > SPARSE_MIN_SPAN and n_filled < SPARSE_MIN_FILLED * n_frames


def longest_empty_run(frames: np.ndarray) -> tuple[int, int]:
    """The longest run of frame numbers without a point between the given ones.

    Parameters
    ----------
    frames
        ``(N,) int64``: the frames that carry a point, sorted, distinct.

    Returns
    -------
    tuple of int
        The frame that carries a point before the run and the one after it; ``(0, 0)``
        when there is no run.
    """
    if frames.size < 2:
        return 0, 0
    gap = int(np.argmax(np.diff(frames)))
    return int(frames[gap]), int(frames[gap + 1])


def is_stray_run(before: int, after: int, n_filled: int) -> bool:
    """Whether an empty run between frames ``before`` and ``after`` splits unrelated data.

    True when the run is longer than :data:`STRAY_GAP_FRAMES` and than the ``n_filled``
    frames that carry a point.
    """
    empty = after - before - 1
    return empty > STRAY_GAP_FRAMES and empty > n_filled


def check_recorded_rate(rate: float, fps: float, path: Path, field: str, *,
                        sidecar: Path | str, clip_id: str, line: int | None = None) -> None:
    """Refuse a file whose recorded frame rate is not one or not the sidecar's ``fps``.

    Parameters
    ----------
    rate
        The rate the file records (C3D ``POINT:RATE``, QTM ``FREQUENCY``), Hz.
    fps
        The sidecar's ``fps``.
    path, field, line
        Where the file records it.
    sidecar, clip_id
        The sidecar blamed when the two differ (the file is the measurement).
    """
    if not math.isfinite(rate) or rate <= 0:
        raise InputError(path, f"{field} {rate:g} is not a frame rate", line=line,
                         field=field)
    if abs(rate - fps) > RATE_TOLERANCE * rate:
        raise InputError(sidecar, f"is {fps:g}, but {Path(path).name} records {field} "
                         f"{rate:g} Hz; set \"fps\": {rate:g}", field="fps", clip_id=clip_id)


def visible(name: str) -> bool:
    """Whether a file name is not hidden (``.name``, macOS ``._name`` included)."""
    return not name.startswith(".")


def folder_files(folder: Path) -> list[Path]:
    """The visible regular files directly in ``folder``, in name order.

    What a folder format reads and what the clip's content hash covers are these files
    (or a subset): hidden files, sub-folders and special files are neither read nor
    hashed.
    """
    return sorted(path for path in folder.iterdir() if visible(path.name) and path.is_file())
