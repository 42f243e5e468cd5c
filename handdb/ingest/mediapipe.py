"""MediaPipe hand landmarks, ``<clip_id>.mediapipe.json``.

MediaPipe's hand landmarker has no file format of its own; handdb accepts this JSON
document, one entry per processed frame::

    {"coordinates": "normalized",
     "frames": [{"frame": 0, "handedness": "Right", "score": 0.97,
                 "landmarks": [[x, y, z], ...]},
                {"frame": 1, "landmarks": null}]}

``coordinates`` is ``"normalized"`` (the default: ``x, y`` in [0, 1] of the image width
and height, which the sidecar's ``image`` must give) or ``"pixels"``. ``landmarks`` holds
the 21 landmarks in MediaPipe's order (the ``mediapipe21`` order) as ``[x, y, z]`` or
``[x, y, z, visibility]``; ``z`` (MediaPipe's relative depth) is not used. A frame with
``landmarks`` null or absent, or a frame not listed, has every point missing. A point's
confidence is its ``visibility`` if given, else the frame's ``score`` (the hand detection
confidence), else none. ``handedness`` is informational: MediaPipe labels hands as seen
in a mirrored image, so it is not checked against the sidecar's hand.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from handdb.clip import ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, correspondence, load_skeleton
from handdb.ingest.jsondoc import finite_number, load_json, number_array
from handdb.ingest.observations import Observations, single_file_rows
from handdb.ingest.registry import InputFormat

#: MediaPipe's hand landmarks in order: the ``mediapipe21`` joints.
HAND_SKELETON = "mediapipe21"

COORDINATE_SYSTEMS = ("normalized", "pixels")

#: Values per landmark: x, y, z, and optionally visibility.
LANDMARK_WIDTHS = (3, 4)


def _image_scale(doc: dict, path: Path, spec: ClipSpec) -> np.ndarray:
    """Pixels per coordinate unit along x and y, ``(2,) float64``."""
    system = doc.get("coordinates", "normalized")
    if system not in COORDINATE_SYSTEMS:
        raise InputError(path, f"must be one of {', '.join(COORDINATE_SYSTEMS)}, got "
                         f"{json.dumps(system)}", field="coordinates")
    if system == "pixels":
        return np.ones(2)
    if spec.image_width is None or spec.image_height is None:
        raise InputError(spec.path, "normalized MediaPipe coordinates need the image size: "
                         'add "image": {"width": W, "height": H} (pixels), or write pixel '
                         'coordinates with "coordinates": "pixels"', field="image",
                         clip_id=spec.clip_id)
    return np.array([spec.image_width, spec.image_height], dtype=np.float64)


def _frame_number(entry: Any, path: Path, where: str) -> int:
    if not isinstance(entry, dict):
        raise InputError(path, "must be an object with 'frame' and 'landmarks'", field=where)
    frame = entry.get("frame")
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
        raise InputError(path, f"must be a whole number from 0, got {json.dumps(frame)}",
                         field=f"{where}.frame")
    return frame


def _landmarks(entry: dict, path: Path, where: str, n_points: int) -> np.ndarray | None:
    """``(21, 3)`` x, y and confidence of one frame, or ``None`` without a hand."""
    if entry.get("landmarks") is None:
        return None
    landmarks = number_array(entry["landmarks"], path, f"{where}.landmarks", (n_points, -1))
    if landmarks.shape[1] not in LANDMARK_WIDTHS:
        raise InputError(path, f"landmarks have {landmarks.shape[1]} values; give [x, y, z] "
                         "or [x, y, z, visibility]", field=f"{where}.landmarks")
    if landmarks.shape[1] == 4:
        confidence = landmarks[:, 3]
        field = f"{where}.landmarks"
    elif "score" in entry:
        confidence = np.full(n_points, finite_number(entry["score"], path, f"{where}.score"))
        field = f"{where}.score"
    else:
        confidence = np.full(n_points, np.nan)
        field = ""
    if ((confidence < 0) | (confidence > 1)).any():
        raise InputError(path, "confidence must lie in [0, 1]", field=field)
    return np.column_stack([landmarks[:, :2], confidence])


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Observations:
    """Read a MediaPipe landmarks JSON file (layout in the module docstring).

    Raises
    ------
    InputError
        Naming the JSON path (``frames[3].landmarks``) at fault, or the sidecar's
        ``image`` if normalised coordinates come without an image size.
    """
    path = Path(path)
    doc = load_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("frames"), list):
        raise InputError(path, "must be an object with a 'frames' list", field="frames")
    if not doc["frames"]:
        raise InputError(path, "lists no frames", field="frames")
    scale = _image_scale(doc, path, spec)
    hand = load_skeleton(HAND_SKELETON)
    first_entry: dict[int, int] = {}
    frames, points = [], []
    for i, entry in enumerate(doc["frames"]):
        where = f"frames[{i}]"
        frame = _frame_number(entry, path, where)
        if frame in first_entry:
            raise InputError(path, f"frame {frame} is also frames[{first_entry[frame]}]; keep "
                             "one entry per frame", field=f"{where}.frame")
        first_entry[frame] = i
        landmarks = _landmarks(entry, path, where, hand.n_joints)
        if landmarks is not None:
            frames.append(frame)
            points.append(landmarks)
    kept, joint = correspondence(hand, skeleton)
    points_array = np.array(points).reshape(-1, hand.n_joints, 3)[:, kept]
    uv = points_array[..., :2] * scale
    source, files = single_file_rows(path, uv.shape[0] * kept.size)
    return Observations(
        frame=np.repeat(np.array(frames, dtype=np.int64), kept.size),
        joint=np.tile(joint, len(frames)),
        u=uv[..., 0].ravel(),
        v=uv[..., 1].ravel(),
        confidence=points_array[..., 2].ravel(),
        line=np.zeros(source.size, dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=max(first_entry) + 1,
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
    present[:, dst] = np.isfinite(uv[:, src]).all(axis=-1)
    landmarks = np.zeros((uv.shape[0], hand.n_joints, 4))
    landmarks[:, dst, :2] = uv[:, src] / scale
    landmarks[:, dst, 3] = 1.0 if confidence is None else np.nan_to_num(confidence[:, src])
    landmarks[~present] = 0.0
    frames = [{"frame": t, "landmarks": frame.tolist() if present[t].any() else None}
              for t, frame in enumerate(landmarks)]
    doc = {"coordinates": "pixels" if image_size is None else "normalized", "frames": frames}
    Path(path).write_text(json.dumps(doc))


FORMAT = InputFormat(name="mediapipe", suffix=".mediapipe.json", kind="tracks", read=read,
                     write=write)
