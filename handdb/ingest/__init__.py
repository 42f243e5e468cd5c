"""Readers of the inbox: raw 2D tracks in every supported format, and ground truth.

Every format is registered here, in one place (:data:`handdb.ingest.registry.FORMATS`);
``docs/input-formats.md`` describes each exactly. Typical use::

    scan = discover(inbox)
    for entry in scan.clips:
        clip = load_clip(entry)            # raises InputError on bad input
        tracks = tracks_2d_table(clip)
"""

from handdb.ingest import (
    c3d,
    dhg,
    dlc,
    interhand,
    markers_csv,
    maya,
    mediapipe,
    mediapipe_csv,
    mediapipe_world,
    openpose,
    qtm,
    tracks_csv,
    truth_csv,
    xray,
)
from handdb.ingest.clip_tables import tracks_2d_table, truth_3d_table
from handdb.ingest.inbox import (
    ClipEntry,
    InboxScan,
    clip_content_hash,
    discover,
    inbox_relative,
    load_clip,
)
from handdb.ingest.observations import Observations, Positions
from handdb.ingest.registry import (
    InputFormat,
    get_format,
    register_format,
    registered_formats,
)

for _module in (tracks_csv, openpose, dlc, mediapipe, mediapipe_csv, maya, truth_csv,
                markers_csv, c3d, qtm, interhand, dhg, mediapipe_world, xray):
    register_format(_module.FORMAT)
del _module

#: Version of reading the inbox's files into a clip. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 5

__all__ = [
    "ClipEntry",
    "InboxScan",
    "InputFormat",
    "Observations",
    "Positions",
    "clip_content_hash",
    "inbox_relative",
    "discover",
    "get_format",
    "load_clip",
    "register_format",
    "registered_formats",
    "tracks_2d_table",
    "truth_3d_table",
]
