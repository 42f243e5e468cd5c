"""MediaPipe hand landmarks saved as JSON, ``<clip_id>.mediapipe.json``.

MediaPipe's hand landmarker has no file format of its own; handdb accepts what scripts
save from it, one entry per processed frame::

    {"coordinates": "normalized",
     "frames": [{"frame": 0, "handedness": "Right", "score": 0.97,
                 "landmarks": [[x, y, z], ...]},
                {"frame": 1, "landmarks": null}]}

An entry's ``landmarks`` are 21 ``[x, y, z]`` / ``[x, y, z, visibility]`` lists or
21 ``{"x", "y", "z"[, "visibility", "presence"]}`` objects (the legacy solution's
landmarks), in MediaPipe's order (the ``mediapipe21`` order). An entry may instead be a
MediaPipe Tasks ``HandLandmarkerResult`` saved with ``dataclasses.asdict``
(``handedness``, ``hand_landmarks``, ``hand_world_landmarks``: one list per hand), with
its ``frame`` or its ``timestamp_ms`` (then frame = timestamp x fps / 1000); a document
that is one such result is one frame. A top-level list of entries is accepted when each
entry has its frame; a list of bare hands is refused, as frames without a hand were lost.

``coordinates`` (the document's, else the sidecar's) is ``"normalized"`` (the default:
``x, y`` in [0, 1] of the image, which the sidecar's ``image`` must give; values beyond
[-0.5, 1.5] are refused as probably pixels, and a hand centred at the origin in every
frame as world landmarks) or ``"pixels"``. ``z`` is not used. A frame without a hand, or
not listed, has every point missing.

Which hand, when an entry holds several: the sidecar's ``hand_index`` (its position in
the entry's list, MediaPipe's detection order) or ``handedness`` (its label exactly as
written, e.g. ``"Right"``; MediaPipe's labels depend on mirroring, so they are not checked
against the sidecar's ``hand``). Without either, no entry may hold two hands.

Confidence: each landmark's ``visibility`` when some is non-zero (MediaPipe's hand model
leaves every visibility and presence at 0, which means no confidence), else the hand's
score (``score``, or the Tasks handedness score), else none.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from handdb.clip import ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, correspondence, load_skeleton
from handdb.ingest.jsondoc import finite_number, load_json, number_array, preview
from handdb.ingest.limits import MAX_FRAMES, frame_limit_reason
from handdb.ingest.observations import Observations, resolve_names, single_file_rows
from handdb.ingest.registry import InputFormat

#: MediaPipe's hand landmarks in order: the ``mediapipe21`` joints.
HAND_SKELETON = "mediapipe21"

COORDINATE_SYSTEMS = ("normalized", "pixels")

#: Values per landmark list: x, y, z, and optionally visibility.
LANDMARK_WIDTHS = (3, 4)

#: Normalised coordinates beyond these bounds are not a hand in (or near) the image.
NORMALISED_RANGE = (-0.5, 1.5)

#: A hand whose landmarks centre within this of the origin in every frame, in normalised
#: coordinates, holds MediaPipe's world landmarks (metres around the hand's centre), not
#: image ones: an image hand centred there would sit at the image's top-left corner, mostly
#: outside it, all the time.
WORLD_CENTRE_BOUND = 0.05

#: Milliseconds per second, for Tasks timestamps.
MS_PER_SECOND = 1000.0

#: Keys of a Tasks ``HandLandmarkerResult``.
TASKS_LANDMARKS, TASKS_WORLD, TASKS_HANDEDNESS = (
    "hand_landmarks", "hand_world_landmarks", "handedness")


@dataclass(frozen=True)
class Hand:
    """One hand of one frame as MediaPipe reported it.

    Attributes
    ----------
    label
        Its handedness label (``"Left"``/``"Right"``), or ``None``.
    score
        Its detection or handedness score in [0, 1], or ``None``.
    landmarks
        ``(21, 3) float64`` x, y, z image landmarks, or ``None``.
    visibility
        ``(21,) float64`` per-landmark visibility, or ``None``.
    world
        ``(21, 3) float64`` world landmarks in metres, or ``None``.
    field
        JSON path of the hand's image landmarks, for messages.
    """

    label: str | None
    score: float | None
    landmarks: np.ndarray | None
    visibility: np.ndarray | None
    world: np.ndarray | None
    field: str


def _landmark_list(value: Any, path: Path, field: str, n_points: int
                   ) -> tuple[np.ndarray, np.ndarray | None]:
    """``(21, 3)`` x, y, z and ``(21,)`` visibility (or ``None``) of a landmark list."""
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        rows = []
        for k, landmark in enumerate(value):
            for axis in ("x", "y"):
                if axis not in landmark:
                    raise InputError(path, f"needs '{axis}'", field=f"{field}[{k}]")
            rows.append([landmark[axis] if axis in landmark else 0.0 for axis in "xyz"]
                        + ([landmark["visibility"]] if "visibility" in landmark else []))
        value = rows
    array = number_array(value, path, field, (n_points, -1))
    if array.shape[1] not in LANDMARK_WIDTHS:
        raise InputError(path, f"landmarks have {array.shape[1]} values; give [x, y, z] or "
                         "[x, y, z, visibility]", field=field)
    return array[:, :3], (array[:, 3] if array.shape[1] == 4 else None)


def _frame_of(entry: dict, path: Path, where: str, spec: ClipSpec) -> int:
    """The frame number of an entry: its ``frame``, or its ``timestamp_ms`` at ``fps``."""
    if "frame" not in entry and "timestamp_ms" in entry:
        stamp = finite_number(entry["timestamp_ms"], path, f"{where}.timestamp_ms")
        frame = round(stamp * spec.fps / MS_PER_SECOND)
        field = f"{where}.timestamp_ms"
    else:
        given = entry.get("frame")
        field = f"{where}.frame"
        if isinstance(given, bool) or not isinstance(given, int) or given < 0:
            raise InputError(path, f"must be a whole number from 0, got {preview(given)}",
                             field=field)
        frame = given
    if frame < 0:
        raise InputError(path, "must not be negative", field=field)
    if frame >= MAX_FRAMES:
        raise InputError(path, frame_limit_reason(frame), field=field)
    return frame


def _tasks_hands(entry: dict, path: Path, where: str, n_points: int) -> list[Hand]:
    """The hands of a Tasks ``HandLandmarkerResult`` entry."""
    image = entry.get(TASKS_LANDMARKS) or []
    world = entry.get(TASKS_WORLD) or []
    labels = entry.get(TASKS_HANDEDNESS) or []
    for key, value in ((TASKS_LANDMARKS, image), (TASKS_WORLD, world),
                       (TASKS_HANDEDNESS, labels)):
        if not isinstance(value, list):
            raise InputError(path, f"must be a list with one entry per hand, got "
                             f"{preview(value)}", field=f"{where}.{key}")
    hands = []
    for k in range(max(len(image), len(world))):
        field = f"{where}.{TASKS_LANDMARKS}[{k}]"
        xyz, visibility = (_landmark_list(image[k], path, field, n_points) if k < len(image)
                           else (None, None))
        world_xyz = (_landmark_list(world[k], path, f"{where}.{TASKS_WORLD}[{k}]",
                                    n_points)[0] if k < len(world) else None)
        category = labels[k][0] if k < len(labels) and isinstance(labels[k], list) \
            and labels[k] and isinstance(labels[k][0], dict) else {}
        score = category.get("score")
        hands.append(Hand(
            label=category.get("category_name"),
            score=None if score is None else finite_number(
                score, path, f"{where}.{TASKS_HANDEDNESS}[{k}][0].score"),
            landmarks=xyz, visibility=visibility, world=world_xyz, field=field))
    return hands


def _legacy_hand(entry: dict, path: Path, where: str, n_points: int) -> list[Hand]:
    """The one hand (or none) of a legacy entry with ``landmarks``."""
    if entry.get("landmarks") is None and entry.get("world_landmarks") is None:
        return []
    field = f"{where}.landmarks"
    xyz, visibility = (_landmark_list(entry["landmarks"], path, field, n_points)
                       if entry.get("landmarks") is not None else (None, None))
    world = (_landmark_list(entry["world_landmarks"], path, f"{where}.world_landmarks",
                            n_points)[0] if entry.get("world_landmarks") is not None else None)
    label = entry.get("handedness")
    return [Hand(label=label if isinstance(label, str) else None,
                 score=finite_number(entry["score"], path, f"{where}.score")
                 if "score" in entry else None,
                 landmarks=xyz, visibility=visibility, world=world, field=field)]


def _entries(doc: Any, path: Path) -> tuple[list[Any], str]:
    """The per-frame entries of a document and the JSON path prefix of each."""
    if isinstance(doc, dict) and isinstance(doc.get("frames"), list):
        return doc["frames"], "frames"
    if isinstance(doc, dict) and TASKS_LANDMARKS in doc and "frames" not in doc:
        return [{"frame": 0} | doc], "result"
    if isinstance(doc, list) and doc and all(
            isinstance(e, dict) and ("frame" in e or "timestamp_ms" in e) for e in doc):
        return doc, ""
    if isinstance(doc, list):
        raise InputError(path, "is a list of hands without frame numbers; frames where "
                         "MediaPipe found no hand were probably dropped, so handdb cannot "
                         'place the rest in time. Save {"frame": i, "landmarks": [...]} per '
                         "frame", field="frames")
    raise InputError(path, "must be an object with a 'frames' list", field="frames")


def read_hands(path: Path, spec: ClipSpec) -> tuple[dict[str, Any], dict[int, Hand], int]:
    """Read a MediaPipe JSON document and pick the clip's hand in every frame.

    Returns
    -------
    doc
        The document's top-level object (``{}`` for a list).
    hands
        Frame number -> the clip's hand, for frames where it was found.
    n_frames
        One more than the largest frame number listed.

    Raises
    ------
    InputError
        Naming the JSON path at fault, or the sidecar key to give.
    """
    doc = load_json(path)
    entries, prefix = _entries(doc, path)
    if not entries:
        raise InputError(path, "lists no frames", field="frames")
    n_points = load_skeleton(HAND_SKELETON).n_joints
    first_entry: dict[int, int] = {}
    found: dict[int, list[Hand]] = {}
    for i, entry in enumerate(entries):
        where = f"{prefix}[{i}]" if prefix != "result" else prefix
        if not isinstance(entry, dict):
            raise InputError(path, "must be an object with 'frame' and 'landmarks'",
                             field=where)
        frame = _frame_of(entry, path, where, spec)
        if frame in first_entry:
            raise InputError(path, f"frame {frame} is also {prefix}[{first_entry[frame]}]; "
                             "keep one entry per frame", field=f"{where}.frame")
        first_entry[frame] = i
        tasks = TASKS_LANDMARKS in entry or TASKS_WORLD in entry
        found[frame] = (_tasks_hands if tasks else _legacy_hand)(entry, path, where, n_points)
    return (doc if isinstance(doc, dict) else {}), _pick(found, path, spec), max(first_entry) + 1


def _pick(found: dict[int, list[Hand]], path: Path, spec: ClipSpec) -> dict[int, Hand]:
    """The clip's hand in each frame, by the sidecar's ``hand_index`` or ``handedness``."""
    sidecar = Path(spec.path).name
    if spec.hand_index is not None:
        return {f: hands[spec.hand_index] for f, hands in found.items()
                if len(hands) > spec.hand_index}
    if spec.handedness is not None:
        picked = {}
        for frame, hands in found.items():
            matching = [hand for hand in hands if hand.label == spec.handedness]
            if len(matching) > 1:
                raise InputError(path, f"frame {frame} holds two hands labelled "
                                 f"{json.dumps(spec.handedness)}; select by \"hand_index\" in "
                                 f"{sidecar} instead", field=matching[1].field)
            if matching:
                picked[frame] = matching[0]
        return picked
    crowded = next(((f, hands) for f, hands in sorted(found.items()) if len(hands) > 1), None)
    if crowded is not None:
        frame, hands = crowded
        labels = ", ".join(json.dumps(hand.label) for hand in hands if hand.label)
        by_label = f' or "handedness" ({labels})' if labels else ""
        raise InputError(path, f"frame {frame} holds {len(hands)} hands; say which one this "
                         f'clip is with "hand_index": 0 to {len(hands) - 1} (MediaPipe\'s '
                         f"detection order){by_label} in {sidecar}, one sidecar per hand",
                         field=hands[1].field)
    return {frame: hands[0] for frame, hands in found.items() if hands}


def confidence_of(visibility: np.ndarray | None, score: float | None, path: Path,
                  field: str, n_points: int) -> np.ndarray:
    """Per-landmark confidence ``(21,)``: visibility, else the hand's score, else NaN.

    All-zero visibility is MediaPipe's default for hand landmarks and means none.

    Raises
    ------
    InputError
        For visibility or a score outside [0, 1] (a logit).
    """
    if visibility is not None and visibility.any():
        if ((visibility < 0) | (visibility > 1)).any():
            bad = visibility[(visibility < 0) | (visibility > 1)][0]
            raise InputError(path, f"visibility {bad:g} is not in [0, 1] (a logit?); drop the "
                             "visibility values, MediaPipe's hand model does not produce them",
                             field=field)
        return visibility
    if score is None:
        return np.full(n_points, np.nan)
    if not 0.0 <= score <= 1.0:
        raise InputError(path, f"score {score:g} is not in [0, 1]", field=field)
    return np.full(n_points, score)


def coordinate_system(doc: dict[str, Any], path: Path, spec: ClipSpec) -> str:
    """``"normalized"`` or ``"pixels"``: the document's ``coordinates``, else the sidecar's."""
    given = doc.get("coordinates")
    if given is not None and given not in COORDINATE_SYSTEMS:
        raise InputError(path, f"must be one of {', '.join(COORDINATE_SYSTEMS)}, got "
                         f"{preview(given)}", field="coordinates")
    if spec.coordinates is not None and spec.coordinates not in COORDINATE_SYSTEMS:
        raise InputError(spec.path, f"must be one of {', '.join(COORDINATE_SYSTEMS)} for "
                         "MediaPipe", field="coordinates", clip_id=spec.clip_id)
    if given is not None and spec.coordinates is not None and given != spec.coordinates:
        raise InputError(spec.path, f"says {spec.coordinates}, but {path.name} says {given}; "
                         "remove the sidecar's key", field="coordinates", clip_id=spec.clip_id)
    return given or spec.coordinates or "normalized"


def image_scale(system: str, spec: ClipSpec) -> np.ndarray:
    """Pixels per coordinate unit along x and y, ``(2,) float64``."""
    if system == "pixels":
        return np.ones(2)
    if spec.image_width is None or spec.image_height is None:
        raise InputError(spec.path, "normalized MediaPipe coordinates need the image size: "
                         'add "image": {"width": W, "height": H} (pixels), or write pixel '
                         'coordinates with "coordinates": "pixels"', field="image",
                         clip_id=spec.clip_id)
    return np.array([spec.image_width, spec.image_height], dtype=np.float64)


def outside_image(xy: np.ndarray) -> tuple[int, int] | None:
    """The first ``(point, axis)`` of normalised ``xy`` ``(N, 2)`` beyond the image.

    Either axis counts (:data:`NORMALISED_RANGE`); ``None`` when every value lies within.
    """
    low, high = NORMALISED_RANGE
    outside = np.argwhere((xy < low) | (xy > high))
    return (int(outside[0, 0]), int(outside[0, 1])) if outside.size else None


def outside_image_reason(value: float, axis: int) -> str:
    """Why a normalised coordinate ``value`` on ``axis`` (0: x, 1: y) is refused."""
    low, high = NORMALISED_RANGE
    return (f"{'xy'[axis]}={value:g} lies far outside the image (normalised coordinates lie "
            f"within [{low}, {high}]); are these pixels? Set \"coordinates\": \"pixels\" in the "
            "sidecar")


def check_normalised(xy: np.ndarray, path: Path, field: str) -> None:
    """Refuse normalised landmarks ``xy`` ``(21, 2)`` beyond the image on either axis.

    Raises
    ------
    InputError
        Naming ``path`` and the landmark (``frames[3].landmarks[5]``).
    """
    found = outside_image(xy)
    if found is not None:
        k, axis = found
        raise InputError(path, f"landmark {k} at {outside_image_reason(xy[k, axis], axis)}",
                         field=f"{field}[{k}]")


def check_not_world(xy: np.ndarray, path: Path, where: str) -> None:
    """Refuse normalised landmarks that are MediaPipe's world landmarks.

    Parameters
    ----------
    xy
        ``(F, 21, 2) float64``: the ``x, y`` of every frame's hand, normalised; NaN where a
        landmark is absent.
    path
        The file, for the message.
    where
        Where the landmarks are in the file, for the message.

    Raises
    ------
    InputError
        If every frame's hand centres within :data:`WORLD_CENTRE_BOUND` of the origin.
    """
    if not xy.size or not np.isfinite(xy).any():
        return
    centres = np.nanmean(xy, axis=1)
    if np.nanmax(np.abs(centres)) < WORLD_CENTRE_BOUND:
        raise InputError(path, "every frame's hand centres within "
                         f"{WORLD_CENTRE_BOUND:g} of the origin: these are MediaPipe's world "
                         "landmarks (metres around the hand), not image ones; save the image "
                         "landmarks (hand_landmarks) here and read world landmarks as "
                         "<clip_id>.mediapipe-world.json (a hand truly at the image's corner: "
                         'give pixels with "coordinates": "pixels")', field=where)


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a MediaPipe landmarks JSON file (layouts in the module docstring).

    Raises
    ------
    InputError
        Naming the JSON path (``frames[3].landmarks``) at fault, or the sidecar key
        (``image``, ``hand_index``, ``handedness``) to give.
    """
    path = Path(path)
    doc, hands, n_frames = read_hands(path, spec)
    normalised = coordinate_system(doc, path, spec) == "normalized"
    scale = image_scale("normalized" if normalised else "pixels", spec)
    hand = load_skeleton(HAND_SKELETON)
    joints = resolve_names(hand.joints, spec, skeleton, path,
                           lambda k: (None, "landmarks"), fixed=True)
    kept = np.flatnonzero(joints >= 0)
    frames, points = [], []
    for frame, found in sorted(hands.items()):
        if found.landmarks is None:
            continue
        if normalised:
            check_normalised(found.landmarks[:, :2], path, found.field)
        confidence = confidence_of(found.visibility, found.score, path, found.field,
                                   hand.n_joints)
        frames.append(frame)
        points.append(np.column_stack([found.landmarks[:, :2] * scale, confidence]))
    points_array = np.array(points).reshape(-1, hand.n_joints, 3)[:, kept]
    if normalised:
        check_not_world(points_array[..., :2] / scale, path, "landmarks")
    source, files = single_file_rows(path, points_array.shape[0] * kept.size)
    return Observations(
        frame=np.repeat(np.array(frames, dtype=np.int64), kept.size),
        joint=np.tile(joints[kept], len(frames)),
        u=points_array[..., 0].ravel(),
        v=points_array[..., 1].ravel(),
        confidence=points_array[..., 2].ravel(),
        line=np.zeros(source.size, dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=n_frames,
        names=frozenset(hand.joints),
        fields={"u": "landmarks.x", "v": "landmarks.y", "confidence": "visibility"},
    )


def write(path: str | Path, uv: np.ndarray, confidence: np.ndarray | None,
          skeleton: Skeleton, *, image_size: tuple[int, int] | None = None) -> None:
    """Write a MediaPipe landmarks JSON file.

    Parameters
    ----------
    path
        The file to write.
    uv
        ``(T, J, 2) float64``, pixels; NaN where the point is missing.
    confidence
        ``(T, J) float64`` in [0, 1], written as each landmark's visibility; ``None``
        for visibility 1 on every point present.
    skeleton
        The skeleton ordering the joint axis.
    image_size
        ``(width, height)`` in pixels to write normalised coordinates, or ``None`` to
        write pixels.

    A frame without any point gets ``"landmarks": null``. MediaPipe reports all 21
    landmarks or none, so a single missing point is written at ``0, 0`` with visibility 0.
    """
    hand = load_skeleton(HAND_SKELETON)
    src, dst = correspondence(skeleton, hand)
    scale = np.ones(2) if image_size is None else np.asarray(image_size, dtype=np.float64)
    present = np.zeros((uv.shape[0], hand.n_joints), dtype=bool)
    present[:, dst] = finite_points(uv[:, src])
    landmarks = np.zeros((uv.shape[0], hand.n_joints, 4))
    landmarks[:, dst, :2] = uv[:, src] / scale
    landmarks[:, dst, 3] = 1.0 if confidence is None else np.nan_to_num(confidence[:, src])
    landmarks[~present] = 0.0
    frames = [{"frame": t, "landmarks": frame.tolist() if present[t].any() else None}
              for t, frame in enumerate(landmarks)]
    doc = {"coordinates": "pixels" if image_size is None else "normalized", "frames": frames}
    Path(path).write_text(json.dumps(doc))


FORMAT = InputFormat(name="mediapipe", suffix=".mediapipe.json", kind="tracks", read=read,
                     write=write, sidecar_keys=("hand_index", "handedness", "coordinates"))
