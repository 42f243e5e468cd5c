"""Readers of the inbox: raw 2D tracks in every supported format, and ground truth.

The formats register themselves in :mod:`handdb.readers.registry`; ``docs/input-formats.md``
describes each exactly. Typical use::

    scan = discover(inbox)
    for entry in scan.clips:
        clip = load_clip(entry)            # raises InputError on bad input
        tracks = tracks_2d_table(clip)
"""

from handdb.readers import (
    c3d,
    dlc,
    markers_csv,
    maya,
    mediapipe,
    openpose,
    tracks_csv,
    truth_csv,
)
from handdb.readers.clip_tables import tracks_2d_table, truth_3d_table
from handdb.readers.inbox import ClipEntry, InboxScan, content_hash, discover, load_clip
from handdb.readers.observations import Observations, Positions
from handdb.readers.registry import (
    InputFormat,
    get_format,
    register_format,
    registered_formats,
)

for _module in (tracks_csv, openpose, dlc, mediapipe, maya, truth_csv, markers_csv, c3d):
    register_format(_module.FORMAT)
del _module

__all__ = [
    "ClipEntry",
    "InboxScan",
    "InputFormat",
    "Observations",
    "Positions",
    "content_hash",
    "discover",
    "get_format",
    "load_clip",
    "register_format",
    "registered_formats",
    "tracks_2d_table",
    "truth_3d_table",
]
