"""DHG-14/28 hand skeletons, ``<clip_id>.dhg.txt`` (3D markers).

The dataset's ``skeletons_world.txt``: one line per frame, 66 numbers separated by blanks,
the 22 joints of the ``dhg22`` skeleton (wrist, palm centre, then four joints a finger
from base to tip) times x, y, z, in metres in the camera's world coordinates (Intel
RealSense SDK). Frames count from 0 in line order. The clip is 3D (kind ``markers``,
no camera needed); with a sidecar skeleton other than ``dhg22``, joints it lacks (the
palm centre for ``mediapipe21``) are dropped.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from handdb.clip import METERS_PER_UNIT, ClipSpec
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.delimited import read_bytes, read_whitespace_separated
from handdb.ingest.observations import Positions, resolve_names, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat

#: The skeleton whose joints a line lists, in order.
DHG_SKELETON = "dhg22"

#: DHG writes metres.
DHG_UNITS = "m"

AXES = "xyz"


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read a DHG skeleton file into long-form 3D points (clip units).

    Raises
    ------
    InputError
        At the first line without 66 numbers, or the first cell that is not a finite
        number.
    """
    path = Path(path)
    dhg = load_skeleton(DHG_SKELETON)
    columns = [f"{joint}.{axis}" for joint in dhg.joints for axis in AXES]
    table = read_whitespace_separated(path, read_bytes(path), names=columns)
    joints = resolve_names(dhg.joints, spec, skeleton, path,
                           lambda k: (int(table.line[0]), columns[3 * k]), fixed=True)
    kept = np.flatnonzero(joints >= 0)
    xyz = np.stack([np.column_stack([table.numbers(f"{dhg.joints[k]}.{axis}",
                                                   allow_empty=False) for axis in AXES])
                    for k in kept], axis=1)
    scale = METERS_PER_UNIT[DHG_UNITS] / spec.meters_per_unit
    n_frames = table.n_rows
    source, files = single_file_rows(path, n_frames * kept.size)
    joint_names = list(skeleton.joints)
    for k in kept:
        joint_names[joints[k]] = dhg.joints[k]
    return Positions(
        frame=np.repeat(np.arange(n_frames, dtype=np.int64), kept.size),
        joint=np.tile(joints[kept], n_frames),
        xyz=xyz.reshape(-1, 3) * scale,
        line=np.repeat(table.line, kept.size),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=n_frames,
        names=frozenset(dhg.joints),
        fields={axis: f"{{joint}}.{axis}" for axis in AXES},
        joint_names=tuple(joint_names),
    )


FORMAT = InputFormat(name="dhg", suffix=".dhg.txt", kind=MARKERS_KIND, read=read)
