"""Optional ground truth, ``<clip_id>.truth.csv``.

A CSV file with the header ``frame,joint,x,y,z``, one row per (frame, joint) with ground
truth: ``x, y, z`` in the clip's units, camera frame (x right, y down, z away from the
camera). Every cell is required; a joint without ground truth in a frame has no row.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec
from handdb.readers.delimited import write_csv
from handdb.readers.long_csv import joint_column, read_long_csv
from handdb.readers.observations import Positions, single_file_rows
from handdb.readers.registry import InputFormat
from handdb.skeletons import Skeleton

COLUMNS = ("frame", "joint", "x", "y", "z")


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read a ``.truth.csv`` file.

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell.
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


def write(path: str | Path, xyz: np.ndarray, skeleton: Skeleton) -> None:
    """Write a ``.truth.csv`` file.

    Parameters
    ----------
    path
        The file to write.
    xyz
        ``(T, J, 3) float64`` in the clip's units, camera frame; rows are written for the
        finite points only.
    skeleton
        The skeleton ordering the joint axis.
    """
    frame, joint = np.nonzero(np.isfinite(xyz).all(axis=-1))
    columns = {"frame": pa.array(frame, pa.int64()),
               "joint": pa.array(np.asarray(skeleton.joints)[joint])}
    columns.update({axis: pa.array(xyz[frame, joint, k]) for k, axis in enumerate("xyz")})
    write_csv(path, columns)


FORMAT = InputFormat(name="truth_csv", suffix=".truth.csv", kind="truth", read=read,
                     write=write)
