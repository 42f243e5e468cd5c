"""The canonical track format, ``<clip_id>.tracks.csv``.

A CSV file with the header ``frame,joint,u,v`` and optionally ``confidence``, one row per
(frame, joint): ``frame`` a whole number from 0, ``joint`` a canonical joint name (or a
name the sidecar's ``joint_map`` maps), ``u, v`` pixels (x right, y down), ``confidence``
in [0, 1]. A missing point has no row, or a row with ``u`` and ``v`` empty.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec, finite_points
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import write_csv
from handdb.ingest.long_csv import FRAME_TYPE, joint_rows, read_long_csv
from handdb.ingest.observations import Observations, single_file_rows
from handdb.ingest.registry import InputFormat

COLUMNS = ("frame", "joint", "u", "v")
OPTIONAL_COLUMNS = ("confidence",)

#: The columns parsed while reading (:func:`~handdb.ingest.delimited.read_delimited`).
TYPES = FRAME_TYPE | dict.fromkeys(("u", "v", "confidence"), pa.float64())


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a ``.tracks.csv`` file.

    Returns
    -------
    Observations
        One row per row of the file, in file order, but for rows of names the sidecar's
        ``joint_map`` ignores.

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell.
    """
    path = Path(path)
    table, joint, names = joint_rows(read_long_csv(path, COLUMNS, OPTIONAL_COLUMNS, TYPES),
                                     "joint", spec, skeleton)
    frame = table.frames("frame")
    confidence = (table.numbers("confidence", allow_empty=True)
                  if "confidence" in table.columns else np.full(table.n_rows, np.nan))
    source, files = single_file_rows(path, table.n_rows)
    return Observations(
        frame=frame,
        joint=joint,
        u=table.numbers("u", allow_empty=True),
        v=table.numbers("v", allow_empty=True),
        confidence=confidence,
        line=table.line,
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
        names=names,
    )


def reported(uv: np.ndarray, confidence: np.ndarray | None) -> np.ndarray:
    """``(T, J) bool``: points a file should carry (a position or a confidence)."""
    present = finite_points(uv)
    return present if confidence is None else present | np.isfinite(confidence)


def write(path: str | Path, uv: np.ndarray, confidence: np.ndarray | None,
          skeleton: Skeleton) -> None:
    """Write a ``.tracks.csv`` file.

    Parameters
    ----------
    path
        The file to write.
    uv
        ``(T, J, 2) float64``, pixels; NaN where the point is missing.
    confidence
        ``(T, J) float64`` in [0, 1] or ``None`` for no confidence column.
    skeleton
        The skeleton ordering the joint axis.

    A missing point gets a row with empty ``u, v`` if it has a confidence, none otherwise.
    """
    frame, joint = np.nonzero(reported(uv, confidence))
    columns = {
        "frame": pa.array(frame, pa.int64()),
        "joint": pa.array(np.asarray(skeleton.joints)[joint]),
        "u": pa.array(uv[frame, joint, 0], from_pandas=True),
        "v": pa.array(uv[frame, joint, 1], from_pandas=True),
    }
    if confidence is not None:
        columns["confidence"] = pa.array(confidence[frame, joint], from_pandas=True)
    write_csv(path, columns)


FORMAT = InputFormat(name="tracks_csv", suffix=".tracks.csv", kind="tracks", read=read,
                     write=write)
