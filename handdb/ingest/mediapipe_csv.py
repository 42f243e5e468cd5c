"""MediaPipe hand landmarks as a long CSV, ``<clip_id>.mediapipe.csv``.

The table scripts write from MediaPipe's results, one row per (frame, hand, landmark)::

    frame,hand,landmark,x,y,z
    0,0,0,0.3067709505558014,0.6454901099205017,3.479058818811609e-07

Columns in any order: ``frame``, ``landmark``, ``x``, ``y`` required; ``z``, ``hand``,
``handedness``, ``score``, ``visibility``, ``presence`` optional. ``landmark`` is the index
0-20 in MediaPipe's order (the ``mediapipe21`` order) or MediaPipe's name (``WRIST``,
``THUMB_CMC``, ..., ``PINKY_TIP``). ``hand`` is the hand's position in MediaPipe's list of
the frame (detection order, not handedness), ``handedness`` its label. Frames without
rows have every point missing; ``z`` and ``presence`` are not used.

Which hand: the sidecar's ``hand_index`` (a value of ``hand``) or ``handedness`` (a
value of ``handedness``, exactly as written); without either the file may hold one hand.
Coordinates are normalised ([0, 1] of the image, the sidecar's ``image`` needed) unless
the sidecar says ``"coordinates": "pixels"``. Confidence as in
:mod:`handdb.ingest.mediapipe`: visibility unless all zero, else ``score``, else none.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.compute as pc

from handdb.clip import ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.delimited import DelimitedTable
from handdb.ingest.limits import quoted
from handdb.ingest.long_csv import read_long_csv
from handdb.ingest.mediapipe import (
    HAND_SKELETON,
    check_not_world,
    coordinate_system,
    image_scale,
    outside_image,
    outside_image_reason,
)
from handdb.ingest.observations import Observations, resolve_names, single_file_rows
from handdb.ingest.registry import InputFormat

COLUMNS = ("frame", "landmark", "x", "y")
OPTIONAL_COLUMNS = ("z", "hand", "handedness", "score", "visibility", "presence")

#: MediaPipe's ``HandLandmark`` names in order (the ``mediapipe21`` order).
LANDMARK_NAMES = (
    "WRIST", "THUMB_CMC", "THUMB_MCP", "THUMB_IP", "THUMB_TIP",
    "INDEX_FINGER_MCP", "INDEX_FINGER_PIP", "INDEX_FINGER_DIP", "INDEX_FINGER_TIP",
    "MIDDLE_FINGER_MCP", "MIDDLE_FINGER_PIP", "MIDDLE_FINGER_DIP", "MIDDLE_FINGER_TIP",
    "RING_FINGER_MCP", "RING_FINGER_PIP", "RING_FINGER_DIP", "RING_FINGER_TIP",
    "PINKY_MCP", "PINKY_PIP", "PINKY_DIP", "PINKY_TIP",
)


def _hand_rows(table: DelimitedTable, spec: ClipSpec) -> DelimitedTable:
    """The rows of the clip's hand, by the sidecar's ``hand_index`` or ``handedness``."""
    sidecar = Path(spec.path).name
    for column, wanted in (("hand", spec.hand_index), ("handedness", spec.handedness)):
        if wanted is None:
            continue
        if column not in table.columns:
            raise InputError(spec.path, f"selects a hand, but {table.path.name} has no "
                             f"'{column}' column", field="hand_index" if column == "hand"
                             else column, clip_id=spec.clip_id)
        values = (table.frames(column) == wanted if column == "hand"
                  else pc.equal(table.columns[column], wanted).to_numpy(zero_copy_only=False))
        if not values.any():
            raise InputError(spec.path, f"is {quoted(str(wanted))}, but no row of "
                             f"{table.path.name} has that {column}",
                             field="hand_index" if column == "hand" else column,
                             clip_id=spec.clip_id)
        return table.take(values)
    for column, key in (("hand", "hand_index"), ("handedness", "handedness")):
        if column in table.columns:
            names, codes = table.dictionary(column)
            if len(names) > 1:
                row = int(np.argmax(codes != codes[0]))
                shown = " and ".join(names[:4])
                values = [n if column == "hand" else f'"{n}"' for n in names[:4]]
                raise table.error(row, column, f"holds hands {shown}; say which one this clip "
                                  f'is with "{key}": {values[0]} (one of {", ".join(values)}) '
                                  f"in {sidecar}, one sidecar per hand")
    return table


def _landmarks(table: DelimitedTable) -> np.ndarray:
    """Landmark index 0-20 of each row, ``(N,) int64``, from numbers or MediaPipe names."""
    names, codes = table.dictionary("landmark")
    index = np.empty(len(names), dtype=np.int64)
    for k, name in enumerate(names):
        if name.isascii() and name.isdigit() and int(name) < len(LANDMARK_NAMES):
            index[k] = int(name)
        elif name.upper() in LANDMARK_NAMES:
            index[k] = LANDMARK_NAMES.index(name.upper())
        else:
            row = int(np.argmax(codes == k))
            raise table.error(row, "landmark", f"{quoted(name)} is not a MediaPipe hand "
                              f"landmark: give 0 to {len(LANDMARK_NAMES) - 1} or a name "
                              f"({LANDMARK_NAMES[0]}, ..., {LANDMARK_NAMES[-1]})")
    return index[codes]


def _confidence(table: DelimitedTable) -> np.ndarray:
    """Per-row confidence: visibility unless all zero, else score, else NaN."""
    if "visibility" in table.columns:
        visibility = table.numbers("visibility", allow_empty=True)
        if np.nan_to_num(visibility).any():
            outside = np.flatnonzero((visibility < 0) | (visibility > 1))
            if outside.size:
                raise table.error(int(outside[0]), "visibility", f"visibility "
                                  f"{visibility[outside[0]]:g} is not in [0, 1] (a logit?); "
                                  "drop the column, MediaPipe's hand model does not produce it")
            return visibility
    if "score" in table.columns:
        return table.numbers("score", allow_empty=True)
    return np.full(table.n_rows, np.nan)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a MediaPipe long CSV file (layout in the module docstring).

    Raises
    ------
    InputError
        Naming the line and column of the first bad cell, or the sidecar key
        (``hand_index``, ``handedness``, ``image``) to give.
    """
    path = Path(path)
    table = _hand_rows(read_long_csv(path, COLUMNS, OPTIONAL_COLUMNS), spec)
    hand = load_skeleton(HAND_SKELETON)
    joints = resolve_names(hand.joints, spec, skeleton, path,
                           lambda k: (None, "landmark"), fixed=True)
    joint = joints[_landmarks(table)]
    table, joint = table.take(joint >= 0), joint[joint >= 0]
    if not table.n_rows:
        raise InputError(path, "holds no row of a landmark the clip keeps (the sidecar's "
                         "joint_map ignores every landmark given)", field="landmark")
    frame = table.frames("frame")
    system = coordinate_system({}, path, spec)
    scale = image_scale(system, spec)
    xy = np.column_stack([table.numbers(axis, allow_empty=True) for axis in "xy"])
    if system == "normalized":
        found = outside_image(xy)
        if found is not None:
            row, axis = found
            raise table.error(row, "xy"[axis], outside_image_reason(xy[row, axis], axis))
        by_frame = np.full((int(frame.max()) + 1, skeleton.n_joints, 2), np.nan)
        by_frame[frame, joint] = xy
        check_not_world(by_frame[np.isfinite(by_frame).any(axis=(1, 2))], path, "x")
    uv = xy * scale
    source, files = single_file_rows(path, table.n_rows)
    return Observations(
        frame=frame,
        joint=joint,
        u=uv[:, 0],
        v=uv[:, 1],
        confidence=_confidence(table),
        line=table.line,
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame.max()) + 1,
        names=frozenset(hand.joints),
        fields={"u": "x", "v": "y", "joint": "landmark"},
    )


FORMAT = InputFormat(name="mediapipe_csv", suffix=".mediapipe.csv", kind="tracks", read=read,
                     sidecar_keys=("hand_index", "handedness", "coordinates"))
