"""OpenPose ``--write_json`` output, a folder ``<clip_id>.openpose/``.

The folder holds one ``<name>_<frame>_keypoints.json`` file per frame; the frame number
is the run of digits before ``_keypoints.json``. Each file is
``{"people": [{"person_id": [-1], "hand_right_keypoints_2d": [x0, y0, c0, ...], ...}]}``:
handdb reads one person's hand on the sidecar's side, 21 points of ``x, y, c`` in
OpenPose's hand order, which is the ``mediapipe21`` order. A point ``0, 0, 0`` is
missing; a file with no people, or whose person's hand array is empty, is a frame with
every point missing. Hidden files (``._name`` of macOS included), sub-folders and other
files are ignored, as by the clip's content hash.

Which person: the sidecar's ``person``, an index into ``people`` (only when every file
with people has the same number of them and they keep their places from file to file:
OpenPose orders people per frame) or
``{"id": n}``, the ``person_id`` OpenPose's tracking gives (a frame without it has every
point missing). Without ``person`` no file may hold more than one person.

Coordinates are pixels unless the sidecar's ``coordinates`` says ``"normalized"``
([0, 1], ``--keypoint_scale 3``) or ``"normalized_signed"`` ([-1, 1],
``--keypoint_scale 4``), which need the sidecar's ``image``. A clip whose every keypoint
lies within [-1, 1] while said to be pixels is refused
(:meth:`~handdb.ingest.observations.Observations.check_pixels`).
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from handdb.clip import ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, correspondence, load_skeleton
from handdb.ingest.jsondoc import load_json, number_array, preview
from handdb.ingest.limits import (
    MAX_FRAMES,
    folder_files,
    frame_limit_reason,
)
from handdb.ingest.observations import Observations, resolve_names
from handdb.ingest.registry import InputFormat

#: OpenPose's hand keypoints in order: the ``mediapipe21`` joints.
HAND_SKELETON = "mediapipe21"

#: Numbers per keypoint: x, y (pixels) and confidence c.
VALUES_PER_POINT = 3

#: The key of each hand's keypoints in a person.
HAND_KEYS = {"right": "hand_right_keypoints_2d", "left": "hand_left_keypoints_2d"}

KEYPOINT_FILE = re.compile(r"(\d+)_keypoints\.json$")

#: Pixels between the centres of two listed people below which they are one person found
#: twice (OpenPose's duplicate detections overlap): which of the two an index picks is the
#: same person either way, so their order is never a trade of places.
SAME_PERSON_PX = 20.0



def frame_files(folder: Path) -> list[tuple[int, Path]]:
    """Return the keypoint files of ``folder`` with their frame numbers, by frame.

    Only the files :func:`~handdb.ingest.limits.folder_files` lists count.

    Raises
    ------
    InputError
        If the folder has no keypoint files, a frame number is beyond
        :data:`~handdb.ingest.limits.MAX_FRAMES`, or two files carry the same frame
        number.
    """
    numbered = []
    for path in folder_files(folder):
        match = KEYPOINT_FILE.search(path.name)
        if match is None:
            continue
        digits = match.group(1).lstrip("0") or "0"
        if len(digits) > len(str(MAX_FRAMES)) or int(digits) >= MAX_FRAMES:
            raise InputError(path, frame_limit_reason(match.group(1)), field="frame")
        numbered.append((int(digits), path))
    numbered.sort()
    if not numbered:
        raise InputError(folder, "holds no '<name>_<frame>_keypoints.json' files")
    for (frame, first), (next_frame, second) in zip(numbered, numbered[1:], strict=False):
        if frame == next_frame:
            raise InputError(second, f"frame {frame} is also in {first.name}; keep one file "
                             "per frame", field="frame")
    return numbered


def _people(path: Path) -> list[dict[str, Any]]:
    """The ``people`` of one keypoint file, each checked to be an object."""
    doc = load_json(path)
    people = doc.get("people") if isinstance(doc, dict) else None
    if not isinstance(people, list):
        raise InputError(path, "needs a 'people' list (OpenPose --write_json output)",
                         field="people")
    for k, person in enumerate(people):
        if not isinstance(person, dict):
            raise InputError(path, f"must be an object, got {preview(person)}",
                             field=f"people[{k}]")
    return people


def _person_id(person: dict[str, Any]) -> int | None:
    """The tracked id of a person (``person_id`` ``[n]`` or ``n``), ``None`` if absent."""
    value = person.get("person_id")
    if isinstance(value, list) and len(value) == 1:
        value = value[0]
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _select(people_by_file: Sequence[tuple[Path, list[dict[str, Any]]]], spec: ClipSpec,
            ) -> list[int | None]:
    """The index in each file's ``people`` of the clip's person (``None``: not there)."""
    sidecar = Path(spec.path).name
    if spec.person_id is not None:
        chosen = []
        for path, people in people_by_file:
            hits = [k for k, person in enumerate(people) if _person_id(person) == spec.person_id]
            if len(hits) > 1:
                raise InputError(path, f"holds person id {spec.person_id} twice",
                                 field=f"people[{hits[1]}].person_id")
            chosen.append(hits[0] if hits else None)
        if all(index is None for index in chosen):
            ids = sorted({str(_person_id(person)) for _, people in people_by_file
                          for person in people})
            raise InputError(spec.path, f"selects person id {spec.person_id}, which no file "
                             f"of the folder holds (its ids: {', '.join(ids) or 'none'}; -1 "
                             "means OpenPose ran without --tracking: select by index)",
                             field="person", clip_id=spec.clip_id)
        return chosen
    counts = [(path, len(people)) for path, people in people_by_file if people]
    if spec.person is None:
        crowded = next(((path, n) for path, n in counts if n > 1), None)
        if crowded is not None:
            path, n = crowded
            raise InputError(path, f"holds {n} people; say which one with \"person\": <index> "
                             f'(0 to {n - 1}) or "person": {{"id": n}} in {sidecar}',
                             field="people")
        return [0 if people else None for _, people in people_by_file]
    for path, n in counts[1:]:
        first, n_first = counts[0]
        if n != n_first:
            here = f"{n} {'person' if n == 1 else 'people'}"
            raise InputError(path, f"{here} here but {n_first} in {first.name}; the order "
                             "of people is not stable across frames, select by "
                             '"person": {"id": n} (run OpenPose with --tracking 1) or split '
                             "the folder", field="people")
    if counts and spec.person >= counts[0][1]:
        path, n = counts[0]
        raise InputError(spec.path, f"is {spec.person}, but {path.name} holds {n} "
                         f"{'person' if n == 1 else 'people'}", field="person",
                         clip_id=spec.clip_id)
    _check_order_kept(people_by_file)
    return [spec.person if people else None for _, people in people_by_file]


def person_centres(people: list[dict[str, Any]]) -> np.ndarray:
    """``(P, 2) float64``: the mean of each person's detected 2D keypoints, pixels.

    Every ``*_keypoints_2d`` array counts (body, face, hands); keypoints of confidence 0
    are not detected. NaN for a person without any.
    """
    centres = np.full((len(people), 2), np.nan)
    for k, person in enumerate(people):
        arrays = [np.asarray(values, dtype=np.float64).reshape(-1, VALUES_PER_POINT)
                  for key, values in person.items()
                  if key.endswith("_keypoints_2d") and isinstance(values, list) and values
                  and len(values) % VALUES_PER_POINT == 0
                  and all(isinstance(v, int | float) for v in values)]
        points = np.concatenate(arrays) if arrays else np.zeros((0, VALUES_PER_POINT))
        detected = points[points[:, 2] > 0, :2]
        if detected.size:
            centres[k] = detected.mean(axis=0)
    return centres


def _check_order_kept(people_by_file: Sequence[tuple[Path, list[dict[str, Any]]]]) -> None:
    """Refuse people who trade places in ``people`` from one frame's file to the next.

    Without ``--tracking`` OpenPose lists people in its own order each frame, so an index
    may follow one person, then another. The people are matched between consecutive files
    with people by their keypoints' centres (:func:`scipy.optimize.linear_sum_assignment`);
    they traded places when the best match is not the listed order and beats it by more
    than the distance between the two nearest people (and :data:`SAME_PERSON_PX`): a jump
    noise cannot make.

    Raises
    ------
    InputError
        Naming the file where the order changes and the people who trade places.
    """
    # imported here: scipy costs a rebuild with nothing to do, which scans every reader
    from scipy.optimize import linear_sum_assignment
    from scipy.spatial.distance import cdist

    previous: tuple[Path, np.ndarray] | None = None
    for path, people in people_by_file:
        if not people:
            continue
        centres = person_centres(people)
        if previous is not None and len(people) > 1 and np.isfinite(centres).all():
            before_path, before = previous
            cost = cdist(before, centres)
            rows, columns = linear_sum_assignment(cost)
            listed = float(np.trace(cost))
            best = float(cost[rows, columns].sum())
            separation = float(np.min(cdist(before, before)[~np.eye(len(before), dtype=bool)]))
            if listed - best > max(separation, SAME_PERSON_PX):
                was = int(rows[columns != rows][0])
                raise InputError(path, f"people[{columns[was]}] here is people[{was}] "
                                 f"of {before_path.name}: OpenPose ran without --tracking and "
                                 "orders people per frame, so an index follows one person, "
                                 'then another; run it with --tracking 1 and select by '
                                 '"person": {"id": n}, or split the folder', field="people")
        previous = (path, centres) if np.isfinite(centres).all() else previous



def hand_keypoints(path: Path, person: dict[str, Any], index: int, hand: str
                   ) -> np.ndarray | None:
    """Return one person's hand keypoints, ``(21, 3)`` x, y, c.

    ``None`` when the person's hand array is empty.

    Raises
    ------
    InputError
        If the person has no array for the hand, or it is not 63 finite numbers.
    """
    key = HAND_KEYS[hand]
    field = f"people[{index}].{key}"
    if key not in person:
        raise InputError(path, f"people[{index}] has no {hand} hand keypoints; run OpenPose "
                         "with --hand, or set the sidecar's hand", field=field)
    values = person[key]
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


def _to_pixels(xy: np.ndarray, missing: np.ndarray, spec: ClipSpec) -> np.ndarray:
    """Keypoints ``(F, 21, 2)`` as pixels by the sidecar's ``coordinates``; NaN if missing."""
    system = spec.coordinates or "pixels"
    if system == "pixels":
        pixels = xy
    else:
        if spec.image_width is None or spec.image_height is None:
            raise InputError(spec.path, f'"coordinates": "{system}" needs the image size: '
                             'add "image": {"width": W, "height": H} (pixels)', field="image",
                             clip_id=spec.clip_id)
        size = np.array([spec.image_width, spec.image_height], dtype=np.float64)
        pixels = (xy + 1.0) / 2.0 * size if system == "normalized_signed" else xy * size
    return np.where(missing[..., None], np.nan, pixels)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read an OpenPose JSON folder.

    Every keypoint of a frame with the clip's person becomes a row; keypoints of joints
    that ``skeleton`` lacks, or that the ``joint_map`` maps to null, are dropped.

    Raises
    ------
    InputError
        Naming the frame's file and the keypoint array at fault, or the sidecar key
        (``person``, ``coordinates``, ``image``) to give.
    """
    folder = Path(path)
    numbered = frame_files(folder)
    people_by_file = [(file, _people(file)) for _, file in numbered]
    chosen = _select(people_by_file, spec)
    with_hand = [(i, frame, index, points) for i, ((frame, file), (_, people), index)
                 in enumerate(zip(numbered, people_by_file, chosen, strict=True))
                 if index is not None
                 and (points := hand_keypoints(file, people[index], index, spec.hand))
                 is not None]
    hand = load_skeleton(HAND_SKELETON)
    joints = resolve_names(hand.joints, spec, skeleton, folder,
                           lambda k: (None, HAND_KEYS[spec.hand]), fixed=True)
    kept = np.flatnonzero(joints >= 0)
    points = np.array([p for *_, p in with_hand]).reshape(
        -1, hand.n_joints, VALUES_PER_POINT)[:, kept]
    missing = (points == 0).all(axis=-1)
    uv = _to_pixels(points[..., :2], missing, spec)
    n_files = np.array([i for i, *_ in with_hand], dtype=np.int64)
    frames = np.array([frame for _, frame, *_ in with_hand], dtype=np.int64)
    key = HAND_KEYS[spec.hand]
    person = (f"people[{spec.person or 0}]" if spec.person_id is None
              else f"people[person_id={spec.person_id}]")
    return Observations(
        frame=np.repeat(frames, kept.size),
        joint=np.tile(joints[kept], len(with_hand)),
        u=uv[..., 0].ravel(),
        v=uv[..., 1].ravel(),
        confidence=points[..., 2].ravel(),
        line=np.zeros(kept.size * len(with_hand), dtype=np.int64),
        source=np.repeat(n_files, kept.size),
        files=tuple(str(file) for _, file in numbered),
        skeleton=skeleton,
        n_frames=numbered[-1][0] + 1,
        names=frozenset(hand.joints),
        fields={name: f"{person}.{key}[{{joint}}].{value}"
                for name, value in (("u", "x"), ("v", "y"), ("confidence", "c"))},
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
    points[~finite_points(points[..., :2])] = 0.0
    stem = folder.name.removesuffix(FORMAT.suffix)
    for t, frame_points in enumerate(points):
        people = []
        if frame_points.any():
            people = [{"person_id": [-1], "pose_keypoints_2d": [],
                       "hand_left_keypoints_2d": [], "hand_right_keypoints_2d": []}
                      | {HAND_KEYS[hand]: frame_points.ravel().tolist()}]
        doc = {"version": 1.3, "people": people}
        (folder / f"{stem}_{t:012d}_keypoints.json").write_text(json.dumps(doc))


def keypoint_files(folder: Path) -> list[Path]:
    """The folder's keypoint files, by frame (see :func:`frame_files`)."""
    return [path for _, path in frame_files(folder)]


FORMAT = InputFormat(name="openpose", suffix=".openpose", kind="tracks", read=read,
                     write=write, directory=True,
                     sidecar_keys=("person", "coordinates"), members=keypoint_files)
