"""Export 3D joint positions as C3D, the biomechanics labs' marker file.

The file is written by the C3D format's own writer, :func:`handdb.ingest.c3d.write`, the
one home of writing C3D in handdb (the reader beside it reads the file back): one
floating-point point per skeleton joint, labelled by the joint's name, ``POINT:RATE`` the
clip's fps, ``POINT:UNITS`` the clip's units; a joint without a position in a frame is a
missing point (residual -1). Coordinates are float32, as in every floating-point C3D.

Axes: the Y-up frame of every handdb export (:func:`handdb.export.markers.y_up_markers`).
Mokka and Vicon Nexus show Z up by default: choose Y up in the viewer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from handdb.export.markers import y_up_markers
from handdb.hand.skeletons import Skeleton
from handdb.ingest import c3d as c3d_format


def export_clip_c3d(path: str | Path, *, skeleton: Skeleton, xyz: np.ndarray, fps: float,
                    units: str) -> Path:
    """Write a clip's 3D joint positions as a C3D file (see the module doc).

    Parameters
    ----------
    path
        Output ``.c3d`` file; its folder must exist.
    skeleton
        Skeleton of ``xyz``: the point labels and their order.
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
    c3d_format.write(path, y_up_markers(xyz, skeleton, fps, units), skeleton, units=units,
                     point_rate=fps)
    return path
