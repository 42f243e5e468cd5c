"""3D marker tracks in C3D files, ``<clip_id>.c3d``, read with the ``c3d`` package.

A C3D file holds labelled 3D points per frame. Each label (trailing blanks dropped) is a
canonical joint name or a name the sidecar's ``joint_map`` maps to one; points with other
labels (extra markers of the capture) are left out. A point the capture lost in a frame
(negative residual) is missing. Coordinates are converted from the file's ``POINT:UNITS``
to the clip's units. C3D frames are numbered from the file's first frame; here from 0.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import c3d
import numpy as np

from handdb.clip import METERS_PER_UNIT, ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.observations import Positions, resolve_joints, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat

#: The C3D parameter that names the point units.
UNITS_PARAMETER = "POINT:UNITS"

#: Point rate written when a clip's frame rate is not given.
DEFAULT_POINT_RATE = 120.0


def _read_points(path: Path) -> tuple[list[str], np.ndarray, str]:
    """Labels, ``(T, N, 4)`` points (x, y, z, residual) and the units of a C3D file."""
    try:
        with path.open("rb") as handle, warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            reader = c3d.Reader(handle)
            labels = [str(label).strip() for label in reader.point_labels]
            units_param = reader.get(UNITS_PARAMETER)
            units = units_param.string_value.strip() if units_param is not None else "mm"
            frames = [points[:, :4].astype(np.float64) for _, points, _ in reader.read_frames()]
    except (ValueError, KeyError, IndexError, EOFError, AssertionError, OSError) as exc:
        raise InputError(path, f"is not a readable C3D file ({exc})") from None
    if not frames:
        raise InputError(path, "holds no frames")
    return labels, np.stack(frames), units


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read the labelled markers of a C3D file into long-form positions (clip units).

    Raises
    ------
    InputError
        If the file is not C3D, has no frames, names units other than mm, cm, m or in,
        names a joint twice, or has no label that is a joint of ``skeleton``.
    """
    path = Path(path)
    labels, points, units = _read_points(path)
    if units not in METERS_PER_UNIT:
        raise InputError(path, f"point units '{units}' are not one of "
                         f"{', '.join(METERS_PER_UNIT)}", field=UNITS_PARAMETER)
    joints = resolve_joints(labels, spec, skeleton)
    known = np.flatnonzero(joints >= 0)
    if not known.size:
        raise InputError(path, f"no point label ({', '.join(labels)}) is a joint of "
                         f"'{skeleton.name}' or in the sidecar's joint_map", field="joint_map",
                         clip_id=spec.clip_id)
    taken, counts = np.unique(joints[known], return_counts=True)
    if (counts > 1).any():
        twice = skeleton.joints[taken[counts > 1][0]]
        raise InputError(path, f"two point labels map to joint '{twice}'", field="joint_map",
                         clip_id=spec.clip_id)
    present = points[:, known, 3] >= 0
    frame, column = np.nonzero(present)
    xyz = points[frame, known[column], :3] * (METERS_PER_UNIT[units] / spec.meters_per_unit)
    source, files = single_file_rows(path, len(frame))
    return Positions(
        frame=frame.astype(np.int64),
        joint=joints[known][column],
        xyz=xyz,
        line=np.zeros(len(frame), dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=len(points),
    )


def write(path: str | Path, markers: np.ndarray, skeleton: Skeleton, *, units: str = "mm",
          point_rate: float = DEFAULT_POINT_RATE) -> None:
    """Write markers as a C3D file (floating point, labelled by canonical joint names).

    Parameters
    ----------
    path
        The file to write.
    markers
        ``(T, J, 3) float64`` in ``units``; NaN markers are written as missing.
    skeleton
        The skeleton ordering the joint axis.
    units
        Units of ``markers``, written to ``POINT:UNITS``.
    point_rate
        Frames per second.
    """
    writer = c3d.Writer(point_rate=point_rate, point_units=units)
    writer.set_point_labels(list(skeleton.joints))
    missing = ~np.isfinite(markers).all(axis=-1)
    points = np.zeros(markers.shape[:2] + (5,), dtype=np.float32)
    points[..., :3] = np.where(missing[..., None], 0.0, markers)
    points[..., 3] = np.where(missing, -1.0, 0.0)
    no_analog = np.zeros((0, 0), dtype=np.float32)
    writer.add_frames([(frame, no_analog) for frame in points])
    with Path(path).open("wb") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        writer.write(handle)


FORMAT = InputFormat(name="c3d", suffix=".c3d", kind=MARKERS_KIND, read=read,
                                     write=write)
