"""The thesis's Maya export, ``<clip_id>.maya.txt``.

The export plug-in of Nopvichai (2009, Figure 4.3 and Appendix C) writes one line per
feature point and frame: ``j<id> <frame> <x> <y> <z>``, whitespace separated, with the
thesis's feature-point ids (the ``thesis21`` skeleton) and Maya world coordinates. Maya's
front view looks down its -z axis with y up; handdb's camera frame has y down and z away
from the camera, so a Maya point ``(x, y, z)`` is the camera-frame point ``(x, -y, -z)``
(a half turn about x). The 2D track is its ``(x, -y)`` and the ground truth the whole
point, in the sidecar's units, without confidence.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.delimited import (
    DelimitedTable,
    read_bytes,
    read_whitespace_separated,
    write_csv,
)
from handdb.ingest.limits import quoted
from handdb.ingest.observations import Observations, Positions, single_file_rows
from handdb.ingest.registry import InputFormat

#: The skeleton whose feature-point ids the export uses.
SKELETON = "thesis21"

#: Sign of each camera-frame axis in Maya world coordinates (front view).
MAYA_TO_CAMERA = np.array([1.0, -1.0, -1.0])

COLUMNS = ("joint", "frame", "x", "y", "z")



def _parse(path: Path, spec: ClipSpec, skeleton: Skeleton,
           ) -> tuple[DelimitedTable, np.ndarray, np.ndarray, np.ndarray, frozenset[str]]:
    """Read the export: the table, frames, joint indices, camera-frame points, point ids."""
    if skeleton.name != SKELETON:
        raise InputError(spec.path, f"a Maya export numbers the feature points of "
                         f"'{SKELETON}'; set the sidecar's skeleton to it",
                         field="skeleton", clip_id=spec.clip_id)
    table = read_whitespace_separated(path, read_bytes(path), names=list(COLUMNS))
    tokens, codes = table.dictionary("joint")
    by_id = {f"j{point_id}": k for k, point_id in enumerate(skeleton.ids)}
    indices = np.array([by_id.get(token, -1) for token in tokens], dtype=np.int64)
    unknown = np.flatnonzero(indices[codes] < 0)
    if unknown.size:
        row = int(unknown[0])
        raise table.error(row, "joint", f"{quoted(tokens[codes[row]])} is not a feature point: "
                          f"write j<id> with an id of {SKELETON} "
                          f"({min(skeleton.ids)}-{max(skeleton.ids)})")
    maya = np.stack([table.numbers(axis, allow_empty=False) for axis in "xyz"], axis=1)
    return (table, table.frames("frame"), indices[codes], maya * MAYA_TO_CAMERA,
            frozenset(tokens))


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read the 2D track of a Maya export: ``u, v = x, -y``, no confidence.

    Raises
    ------
    InputError
        Naming the line and column of the first bad token, or the sidecar's skeleton
        if it is not ``thesis21``.
    """
    path = Path(path)
    table, frame, joint, points, names = _parse(path, spec, skeleton)
    source, files = single_file_rows(path, table.n_rows)
    return Observations(
        frame=frame, joint=joint, u=points[:, 0], v=points[:, 1],
        confidence=np.full(table.n_rows, np.nan), line=table.line, source=source,
        files=files, skeleton=skeleton, n_frames=int(frame.max()) + 1, names=names,
        fields={"u": "x", "v": "y"},
    )


def read_truth(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read the ground truth of a Maya export: camera-frame ``(x, -y, -z)``."""
    path = Path(path)
    table, frame, joint, points, names = _parse(path, spec, skeleton)
    source, files = single_file_rows(path, table.n_rows)
    return Positions(
        frame=frame, joint=joint, xyz=points, line=table.line, source=source, files=files,
        skeleton=skeleton, n_frames=int(frame.max()) + 1, names=names,
    )


def write(path: str | Path, xyz: np.ndarray, skeleton: Skeleton) -> None:
    """Write a Maya export as the thesis's plug-in does, feature point by feature point.

    Parameters
    ----------
    path
        The file to write.
    xyz
        ``(T, J, 3) float64``, camera frame, clip units; points with NaN are left out.
    skeleton
        ``thesis21``, ordering the joint axis.
    """
    if skeleton.name != SKELETON:
        raise ValueError(f"a Maya export holds '{SKELETON}' points, not '{skeleton.name}'")
    joint, frame = np.nonzero(finite_points(xyz).T)
    maya = xyz[frame, joint] * MAYA_TO_CAMERA
    columns = {
        "joint": pa.array([f"j{point_id}" for point_id in np.asarray(skeleton.ids)[joint]]),
        "frame": pa.array(frame, pa.int64()),
    }
    columns.update({axis: pa.array(maya[:, k]) for k, axis in enumerate("xyz")})
    write_csv(path, columns, header=[], delimiter=" ")


FORMAT = InputFormat(name="maya", suffix=".maya.txt", kind="tracks", read=read, write=write,
                     read_truth=read_truth)
