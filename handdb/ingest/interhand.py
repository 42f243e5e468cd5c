"""InterHand2.6M 3D joint annotations, ``<clip_id>.interhand.json`` (3D markers).

The dataset's ``*_joint_3d.json``: ``{"<capture>": {"<frame>": {"world_coord": [[x, y, z]
x 42], "joint_valid": [[1] x 42], "hand_type": "right", "hand_type_valid": true}}}``. Joints
0-20 are the right hand, 21-41 the left, each from the thumb tip down to the wrist (thumb
tip, IP, MCP, CMC; index, middle, ring and little tip, DIP, PIP, MCP; wrist). Coordinates
are millimetres in the capture rig's world frame; a joint with ``joint_valid`` 0 (or
false) is missing whatever its coordinates. The sidecar's ``hand`` picks the half.

Sidecar options: ``capture``, the capture id (required when the file holds more than
one); ``frame_offset``, an integer subtracted from the frame ids, or ``"first"`` to make
the smallest id frame 0. The ids are the dataset's global image numbers, so without an
offset a short clip would start at frame 69148 and is refused as mostly invented.
``hand_type`` is informational.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from handdb.clip import METERS_PER_UNIT, ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.jsondoc import load_json, number_array, preview
from handdb.ingest.limits import MAX_FRAMES, frame_limit_reason, is_sparse, quoted
from handdb.ingest.observations import Positions, resolve_names, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat
from handdb.ingest.sidecar import FIRST_FRAME

#: The joints of one hand in InterHand2.6M's order, by their ``mediapipe21`` names.
HAND_JOINTS = (
    "thumb_tip", "thumb_ip", "thumb_mcp", "thumb_cmc",
    "index_tip", "index_dip", "index_pip", "index_mcp",
    "middle_tip", "middle_dip", "middle_pip", "middle_mcp",
    "ring_tip", "ring_dip", "ring_pip", "ring_mcp",
    "little_tip", "little_dip", "little_pip", "little_mcp",
    "wrist",
)

#: The first joint of each hand in a 42-joint annotation.
HAND_OFFSET = {"right": 0, "left": len(HAND_JOINTS)}

#: InterHand writes millimetres.
INTERHAND_UNITS = "mm"

#: A frame id: a decimal number.
FRAME_ID = re.compile(r"\d{1,18}")


def _capture(doc: Any, path: Path, spec: ClipSpec) -> tuple[str, dict[str, Any]]:
    """The capture the clip is, by the sidecar's ``capture``."""
    if not isinstance(doc, dict) or not doc or not all(isinstance(v, dict) for v in doc.values()):
        raise InputError(path, 'must be an object of captures, {"<capture>": {"<frame>": '
                         '{"world_coord": ..., "joint_valid": ...}}}')
    captures = list(doc)
    if spec.capture is None:
        if len(captures) > 1:
            raise InputError(path, f"holds captures {', '.join(sorted(captures, key=_id_key))}; "
                             f'say which with "capture": "{captures[0]}" in '
                             f"{Path(spec.path).name}", field="capture")
        return captures[0], doc[captures[0]]
    if spec.capture not in doc:
        raise InputError(spec.path, f"is {quoted(spec.capture)}, but {path.name} holds captures "
                         f"{', '.join(sorted(captures, key=_id_key))}", field="capture",
                         clip_id=spec.clip_id)
    return spec.capture, doc[spec.capture]


def _id_key(text: str) -> tuple[int, str]:
    return (len(text), text)


def _frame_numbers(ids: list[str], path: Path, capture: str, spec: ClipSpec) -> np.ndarray:
    """Frame number of each frame id, ``(F,) int64``, by the sidecar's ``frame_offset``."""
    for frame_id in ids:
        if not FRAME_ID.fullmatch(frame_id):
            raise InputError(path, f"frame id {quoted(frame_id)} is not a decimal number",
                             field=f"{capture}.{frame_id}")
    numbers = np.array([int(i) for i in ids], dtype=np.int64)
    offset = spec.frame_offset
    shifted = numbers - (numbers.min() if offset == FIRST_FRAME else int(offset or 0))
    sidecar = Path(spec.path).name
    if (shifted < 0).any():
        bad = ids[int(np.argmin(shifted))]
        raise InputError(path, f"frame id {bad} minus frame_offset {offset} is negative; "
                         'lower frame_offset, or set it to "first"', field=f"{capture}.{bad}")
    if shifted.max() >= MAX_FRAMES or is_sparse(numbers.size, int(shifted.max()) + 1):
        bad = ids[int(np.argmax(shifted))]
        hint = ("" if offset is not None else
                f'; add "frame_offset": "first" to {sidecar} to start the clip at its first id')
        reason = (frame_limit_reason(int(shifted.max())) if shifted.max() >= MAX_FRAMES else
                  f"frame ids start at {numbers.min()} and only {numbers.size} of "
                  f"{shifted.max() + 1} frames carry points")
        raise InputError(path, reason + hint, field=f"{capture}.{bad}")
    return shifted


def _valid(value: Any, path: Path, field: str, n_joints: int) -> np.ndarray:
    """``(42,) bool`` from ``joint_valid``: 0/1 or false/true, bare or in one-element lists."""
    flat = [v[0] if isinstance(v, list) and len(v) == 1 else v for v in value] \
        if isinstance(value, list) else None
    if flat is None or len(flat) != n_joints or any(v not in (0, 1) for v in flat):
        raise InputError(path, f"must be {n_joints} flags 0/1 (or false/true), got "
                         f"{preview(value)}", field=field)
    return np.array(flat, dtype=bool)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read one capture's hand of an InterHand2.6M joint file as 3D markers (clip units).

    Raises
    ------
    InputError
        Naming the JSON path at fault (``3.69148.world_coord``), or the sidecar key
        (``capture``, ``frame_offset``, ``hand``) to give.
    """
    path = Path(path)
    capture, frames = _capture(load_json(path), path, spec)
    ids = list(frames)
    n_all = 2 * len(HAND_JOINTS)
    first = HAND_OFFSET[spec.hand]
    xyz, valid = [], []
    for frame_id in ids:
        where = f"{capture}.{frame_id}"
        entry = frames[frame_id]
        if not isinstance(entry, dict) or "world_coord" not in entry:
            raise InputError(path, "must be an object with world_coord and joint_valid",
                             field=where)
        coords = number_array(entry["world_coord"], path, f"{where}.world_coord", (n_all, 3))
        flags = (_valid(entry["joint_valid"], path, f"{where}.joint_valid", n_all)
                 if "joint_valid" in entry else np.ones(n_all, dtype=bool))
        xyz.append(coords[first:first + len(HAND_JOINTS)])
        valid.append(flags[first:first + len(HAND_JOINTS)])
    frame_numbers = _frame_numbers(ids, path, capture, spec)
    joints = resolve_names(HAND_JOINTS, spec, skeleton, path,
                           lambda k: (None, "world_coord"), fixed=True)
    kept = np.flatnonzero(joints >= 0)
    points, seen = np.array(xyz)[:, kept], np.array(valid)[:, kept]
    if not seen.any():
        raise InputError(path, f"capture {capture} has no valid {spec.hand}-hand joint "
                         '(joint_valid is 0 for all); check the sidecar\'s "hand"',
                         field=f"{capture}.joint_valid")
    row, column = np.nonzero(seen)
    scale = METERS_PER_UNIT[INTERHAND_UNITS] / spec.meters_per_unit
    source, files = single_file_rows(path, row.size)
    return Positions(
        frame=frame_numbers[row],
        joint=joints[kept][column],
        xyz=points[row, column] * scale,
        line=np.zeros(row.size, dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=int(frame_numbers.max()) + 1,
        names=frozenset(HAND_JOINTS),
        fields=dict.fromkeys("xyz", f"{capture}.world_coord"),
    )


FORMAT = InputFormat(name="interhand", suffix=".interhand.json", kind=MARKERS_KIND, read=read,
                     sidecar_keys=("capture", "frame_offset"))
