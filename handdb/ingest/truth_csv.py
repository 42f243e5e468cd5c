"""Optional ground truth, ``<clip_id>.truth.csv``.

A CSV file with the header ``frame,joint,x,y,z``, one row per (frame, joint) with ground
truth: ``x, y, z`` in the clip's units, camera frame (x right, y down, z away from the
camera). Every cell is required; a joint without ground truth in a frame has no row.
Read and written by :func:`handdb.ingest.long_csv.read_positions` and
:func:`~handdb.ingest.long_csv.write_positions`.
"""

from handdb.ingest.long_csv import POSITION_COLUMNS as COLUMNS
from handdb.ingest.long_csv import read_positions as read
from handdb.ingest.long_csv import write_positions as write
from handdb.ingest.registry import InputFormat

__all__ = ["COLUMNS", "FORMAT", "read", "write"]

FORMAT = InputFormat(name="truth_csv", suffix=".truth.csv", kind="truth", read=read,
                     write=write)
