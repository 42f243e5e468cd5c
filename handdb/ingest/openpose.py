"""OpenPose ``--write_json`` output, a folder ``<clip_id>.openpose/``.

The folder holds one ``<name>_<frame>_keypoints.json`` file per frame; the frame number
is the run of digits before ``_keypoints.json``. Each file is
``{"people": [{"hand_right_keypoints_2d": [x0, y0, c0, x1, y1, c1, ...], ...}, ...]}``:
handdb reads the first person's hand on the sidecar's side, 21 points of ``x, y, c``
(pixels and confidence) in OpenPose's hand order, which is the ``mediapipe21`` order. A
point ``0, 0, 0`` is missing; a file with no people, or whose first person's hand array
is empty, is a frame with every point missing. Other files in the folder are ignored.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from handdb.clip import ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, correspondence, load_skeleton
from handdb.ingest.jsondoc import load_json, number_array
from handdb.ingest.observations import Observations
from handdb.ingest.registry import InputFormat

#: OpenPose's hand keypoints in order: the ``mediapipe21`` joints.
HAND_SKELETON = "mediapipe21"

#: Numbers per keypoint: x, y (pixels) and confidence c.
VALUES_PER_POINT = 3

#: The key of each hand's keypoints in a person.
HAND_KEYS = {"right": "hand_right_keypoints_2d", "left": "hand_left_keypoints_2d"}

KEYPOINT_FILE = re.compile(r"(\d+)_keypoints\.json$")


def frame_files(folder: Path) -> list[tuple[int, Path]]:
    """Return the keypoint files of ``folder`` with their frame numbers, by frame.

    Raises
    ------
    InputError
        If the folder has no keypoint files or two files carry the same frame number.
    """
    numbered = sorted(
        (int(match.group(1)), path) for path in folder.iterdir()
        if path.is_file() and (match := KEYPOINT_FILE.search(path.name))
    )
    if not numbered:
        raise InputError(folder, "holds no '<name>_<frame>_keypoints.json' files")
    for (frame, first), (next_frame, second) in zip(numbered, numbered[1:], strict=False):
        if frame == next_frame:
            raise InputError(second, f"frame {frame} is also in {first.name}; keep one file "
                             "per frame", field="frame")
    return numbered


def hand_keypoints(path: Path, hand: str) -> np.ndarray | None:
    """Return the first person's hand keypoints in one file, ``(21, 3)`` x, y, c.

    ``None`` when the file has no people or the person's hand array is empty.
    """
    doc = load_json(path)
    people = doc.get("people") if isinstance(doc, dict) else None
    if not isinstance(people, list):
        raise InputError(path, "needs a 'people' list (OpenPose --write_json output)",
                         field="people")
    if not people:
        return None
    key = HAND_KEYS[hand]
    field = f"people[0].{key}"
    if not isinstance(people[0], dict) or key not in people[0]:
        raise InputError(path, f"the first person has no {hand} hand keypoints; run OpenPose "
                         "with --hand, or set the sidecar's hand", field=field)
    values = people[0][key]
    if values == []:
        return None
    if not isinstance(values, list):
        raise InputError(path, f"must be a list of numbers, got {type(values).__name__}",
                         field=field)
    n_values = len(values)
    n_points = load_skeleton(HAND_SKELETON).n_joints
    if n_values != n_points * VALUES_PER_POINT:
        raise InputError(path, f"has {n_values} numbers; a hand has {n_points} keypoints of "
                         f"x, y, c = {n_points * VALUES_PER_POINT} numbers", field=field)
    return number_array(values, path, field, (n_points * VALUES_PER_POINT,)).reshape(
        n_points, VALUES_PER_POINT)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read an OpenPose JSON folder.

    Every keypoint of a frame with a person becomes a row; keypoints of joints that
    ``skeleton`` lacks are dropped.

    Raises
    ------
    InputError
        Naming the frame's file and the keypoint array at fault.
    """
    folder = Path(path)
    numbered = frame_files(folder)
    with_hand = [(i, frame, points) for i, (frame, file) in enumerate(numbered)
                 if (points := hand_keypoints(file, spec.hand)) is not None]
    hand = load_skeleton(HAND_SKELETON)
    kept, joint = correspondence(hand, skeleton)
    points = np.array([p for _, _, p in with_hand]).reshape(
        -1, hand.n_joints, VALUES_PER_POINT)[:, kept]
    missing = (points == 0).all(axis=-1)
    uv = np.where(missing[..., None], np.nan, points[..., :2])
    n_files = np.array([i for i, _, _ in with_hand], dtype=np.int64)
    frames = np.array([frame for _, frame, _ in with_hand], dtype=np.int64)
    key = HAND_KEYS[spec.hand]
    return Observations(
        frame=np.repeat(frames, kept.size),
        joint=np.tile(joint, len(with_hand)),
        u=uv[..., 0].ravel(),
        v=uv[..., 1].ravel(),
        confidence=points[..., 2].ravel(),
        line=np.zeros(kept.size * len(with_hand), dtype=np.int64),
        source=np.repeat(n_files, kept.size),
        files=tuple(str(file) for _, file in numbered),
        skeleton=skeleton,
        n_frames=numbered[-1][0] + 1,
        fields={name: f"people[0].{key}[{{joint}}].{name[0]}" for name in ("u", "v")}
        | {"confidence": f"people[0].{key}[{{joint}}].c"},
    )


def write(path: str | Path, uv: np.ndarray, confidence: np.ndarray | None,
          skeleton: Skeleton, *, hand: str) -> None:
    """Write an OpenPose JSON folder, one file per frame.

    Parameters
    ----------
    path
        The folder to create (``<clip_id>.openpose``).
    uv
        ``(T, J, 2) float64``, pixels; NaN where the point is missing (written ``0, 0, 0``).
    confidence
        ``(T, J) float64`` in [0, 1], or ``None`` for confidence 1 on every point present.
    skeleton
        The skeleton ordering the joint axis; OpenPose joints it lacks are written missing.
    hand
        ``"left"`` or ``"right"``: which hand's keypoints the people carry.

    A frame without any point is written with no people.
    """
    folder = Path(path)
    folder.mkdir(parents=True, exist_ok=True)
    src, dst = correspondence(skeleton, load_skeleton(HAND_SKELETON))
    conf = np.ones(uv.shape[:2]) if confidence is None else np.nan_to_num(confidence)
    points = np.zeros((uv.shape[0], load_skeleton(HAND_SKELETON).n_joints, VALUES_PER_POINT))
    points[:, dst, :2] = uv[:, src]
    points[:, dst, 2] = conf[:, src]
    points[~np.isfinite(points[..., :2]).all(axis=-1)] = 0.0
    stem = folder.name.removesuffix(FORMAT.suffix)
    for t, frame_points in enumerate(points):
        people = []
        if frame_points.any():
            people = [{"person_id": [-1], "pose_keypoints_2d": [],
                       "hand_left_keypoints_2d": [], "hand_right_keypoints_2d": []}
                      | {HAND_KEYS[hand]: frame_points.ravel().tolist()}]
        doc = {"version": 1.3, "people": people}
        (folder / f"{stem}_{t:012d}_keypoints.json").write_text(json.dumps(doc))


FORMAT = InputFormat(name="openpose", suffix=".openpose", kind="tracks", read=read,
                     write=write, directory=True)
