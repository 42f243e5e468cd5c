"""Export 3D joint positions as TRC, the marker trajectories of OpenSim and Pose2Sim.

A TRC file (Motion Analysis's Track Row Column) is tab-separated text: five header lines,
then one line per frame. Layout as OpenSim reads it and Pose2Sim writes it::

    PathFileType  4         (X/Y/Z)    <file name>
    DataRate      CameraRate  NumFrames  NumMarkers  Units    OrigDataRate  OrigDataStartFrame
        OrigNumFrames
    <fps>         <fps>       <T>        <J>         <units>  <fps>         1   <T>
    Frame#        Time        <joint 1>  ""  ""  <joint 2>  ""  ""  ...
    ""            ""          X1  Y1  Z1  X2  Y2  Z2  ...
    1             0.000000    x   y   z   ...

(the second line is one line in the file).

One marker per skeleton joint, named by the skeleton's joint names in its order. Frames
count from 1 and ``Time`` is ``(frame - 1) / fps`` seconds. A joint without a 3D position
in a frame is three empty cells (OpenSim and pandas read them as NaN).

Axes and units: the Y-up frame of every handdb export, OpenSim's up axis
(:func:`handdb.export.markers.y_up_markers`); lengths in the clip's units, named in ``Units``.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from handdb.clip import finite_points
from handdb.export.markers import y_up_markers
from handdb.hand.skeletons import Skeleton

#: ``PathFileType`` of marker files with X, Y, Z per marker.
PATH_FILE_TYPE = "4\t(X/Y/Z)"

#: Decimals of the coordinates (clip units) and of the time (seconds).
DECIMALS = 6

#: The header's second line: the names of the numbers on its third.
RATE_FIELDS = ("DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units", "OrigDataRate",
               "OrigDataStartFrame", "OrigNumFrames")


def trc_header(name: str, marker_names: tuple[str, ...], n_frames: int, fps: float,
               units: str) -> str:
    """The five header lines of a TRC file, each ending in a newline.

    Parameters
    ----------
    name
        The file's name, written on the first line.
    marker_names
        One name per marker, in column order.
    n_frames
        Frames ``T``.
    fps
        Frames per second.
    units
        Length unit of the coordinates.
    """
    rates = (f"{fps:g}", f"{fps:g}", str(n_frames), str(len(marker_names)), units, f"{fps:g}",
             "1", str(n_frames))
    names = "".join(f"{marker}\t\t\t" for marker in marker_names)
    axes = "\t".join(f"X{k}\tY{k}\tZ{k}" for k in range(1, len(marker_names) + 1))
    return "\n".join([
        f"PathFileType\t{PATH_FILE_TYPE}\t{name}",
        "\t".join(RATE_FIELDS),
        "\t".join(rates),
        f"Frame#\tTime\t{names.rstrip()}\t\t",
        f"\t\t{axes}",
    ]) + "\n"


def trc_rows(xyz: np.ndarray, fps: float) -> str:
    """The data lines of a TRC file: frame number, time, then each marker's ``X Y Z``.

    Parameters
    ----------
    xyz
        ``(T, M, 3) float64`` marker positions; a marker with any non-finite coordinate is
        written as three empty cells.
    fps
        Frames per second.
    """
    n_frames, n_markers = xyz.shape[:2]
    present = finite_points(xyz)
    cells = np.char.mod(f"%.{DECIMALS}f", np.where(present[..., None], xyz, 0.0))
    cells[~present] = ""
    frames = np.arange(1, n_frames + 1)
    times = np.char.mod(f"%.{DECIMALS}f", (frames - 1) / fps)
    text = io.StringIO()
    for frame, time, row in zip(frames, times, cells.reshape(n_frames, 3 * n_markers),
                                strict=True):
        text.write(f"{frame}\t{time}\t" + "\t".join(row) + "\n")
    return text.getvalue()


def export_clip_trc(path: str | Path, *, skeleton: Skeleton, xyz: np.ndarray, fps: float,
                    units: str) -> Path:
    """Write a clip's 3D joint positions as a TRC file (see the module doc).

    Parameters
    ----------
    path
        Output ``.trc`` file; its folder must exist.
    skeleton
        Skeleton of ``xyz``: the marker names and their order.
    xyz, fps, units
        As for :func:`handdb.export.markers.y_up_markers`, which checks them.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ParameterError
        As :func:`~handdb.export.markers.y_up_markers`.
    """
    path = Path(path)
    y_up = y_up_markers(xyz, skeleton, fps, units)
    path.write_text(trc_header(path.name, skeleton.joints, len(xyz), fps, units)
                    + trc_rows(y_up, fps))
    return path
