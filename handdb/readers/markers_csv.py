"""3D marker tracks, ``<clip_id>.markers.csv``.

A CSV file with the header ``frame,joint,x,y,z``: one row per (frame, marker) the capture
saw, ``x, y, z`` in the clip's units, joints named canonically (``mediapipe21``: the
21-marker set of Zhao, Chai & Xu) or through the sidecar's ``joint_map``. A marker the
capture lost in a frame has no row. Every cell of a row is required.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec
from handdb.readers.delimited import write_csv
from handdb.readers.long_csv import joint_column, read_long_csv
from handdb.readers.observations import Positions, single_file_rows
from handdb.readers.registry import MARKERS_KIND, InputFormat, register_format
from handdb.skeletons import Skeleton

COLUMNS = ("frame", "joint", "x", "y", "z")


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read a ``.markers.csv`` file into long-form positions (clip units).

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell: an unknown column, a frame
        that is not a whole number or is negative, an unknown joint, an empty or
        non-numeric coordinate, a marker given twice in a frame.
    """
    path = Path(path)
    table = read_long_csv(path, COLUMNS)
    frame = table.frames("frame")
    source, files = single_file_rows(path, table.n_rows)
    return Positions(
        frame=frame,
        joint=joint_column(table, "joint", spec, skeleton),
        xyz=np.stack([table.numbers(axis, allow_empty=False) for axis in "xyz"], axis=1),
        line=table.line,
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
    )


def write(path: str | Path, markers: np.ndarray, skeleton: Skeleton) -> None:
    """Write a ``.markers.csv`` file.

    Parameters
    ----------
    path
        The file to write.
    markers
        ``(T, J, 3) float64`` in the clip's units; NaN markers get no row.
    skeleton
        The skeleton ordering the joint axis.
    """
    frame, joint = np.nonzero(np.isfinite(markers).all(axis=-1))
    columns = {"frame": pa.array(frame, pa.int64()),
               "joint": pa.array(np.asarray(skeleton.joints)[joint])}
    columns.update({axis: pa.array(markers[frame, joint, k]) for k, axis in enumerate("xyz")})
    write_csv(path, columns)


FORMAT = register_format(InputFormat(name="markers_csv", suffix=".markers.csv",
                                     kind=MARKERS_KIND, read=read, write=write))
