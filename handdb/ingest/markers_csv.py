"""3D marker tracks, ``<clip_id>.markers.csv``.

A CSV file with the header ``frame,joint,x,y,z``: one row per (frame, marker) the capture
saw, ``x, y, z`` in the clip's units, joints named canonically (``mediapipe21``: the
21-marker set of Zhao, Chai & Xu) or through the sidecar's ``joint_map``. A marker the
capture lost in a frame has no row. Every cell of a row is required. The layout is the
ground truth's, read and written by :func:`handdb.ingest.long_csv.read_positions` and
:func:`~handdb.ingest.long_csv.write_positions`.
"""

from handdb.ingest.long_csv import POSITION_COLUMNS as COLUMNS
from handdb.ingest.long_csv import read_positions as read
from handdb.ingest.long_csv import write_positions as write
from handdb.ingest.registry import MARKERS_KIND, InputFormat

__all__ = ["COLUMNS", "FORMAT", "read", "write"]

FORMAT = InputFormat(name="markers_csv", suffix=".markers.csv",
                                     kind=MARKERS_KIND, read=read, write=write)
