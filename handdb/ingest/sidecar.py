"""The sidecar ``<clip_id>.clip.json``: how to read a clip's track file, what it means.

The sidecar says how to read the clip's track file and what the numbers mean::

    {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
     "units": "mm", "camera": {"model": "orthographic"}}

``camera`` may instead be ``{"model": "pinhole", "fx": .., "fy": .., "cx": .., "cy": ..}``
(pixels); a clip whose data file is already 3D (markers) needs no camera. Optional keys:
``bone_lengths`` (child joint -> length in ``units``), ``min_confidence`` (default 0.5;
OpenPose 0.2, :data:`~handdb.clip.FORMAT_MIN_CONFIDENCE`), ``joint_map`` (tool names ->
canonical names, or ``null`` for names to ignore; ``"*": null`` ignores every unmapped
name), ``image`` (``{"width": W, "height": H}``, pixels;
needed for normalised coordinates), ``gap_fill`` and ``lift``
(``{"method": NAME, ...parameters}``), and the reader options of :data:`READER_KEYS`,
each read by the formats that name it in their ``sidecar_keys``.

A sidecar is JSON within the limits of :func:`handdb.ingest.jsondoc.parse_json` (no key
given twice) and at most :data:`~handdb.ingest.limits.MAX_SIDECAR_BYTES` long; a UTF-8
byte-order mark is allowed.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Collection
from pathlib import Path
from typing import Any

from handdb.clip import (
    CAMERA_MODELS,
    HANDS,
    METERS_PER_UNIT,
    NO_CAMERA,
    Camera,
    ClipSpec,
)
from handdb.errors import InputError, SkeletonError
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.jsondoc import parse_json, preview
from handdb.ingest.limits import (
    BONE_LENGTH_RANGE_METRES,
    HAND_LENGTH_RANGE_METRES,
    MAX_FPS,
    MAX_IMAGE_SIDE,
    MAX_SIDECAR_BYTES,
    MIN_FPS,
    quoted,
    read_input,
)
from handdb.ingest.registry import FORMATS

#: A clip id, matched against the whole name: letters, digits, ``.``, ``_``, ``-``; no
#: path separators, not ``..``, no line break.
CLIP_ID_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,127}")

PINHOLE_KEYS = ("fx", "fy", "cx", "cy")

#: The ``joint_map`` key that ignores every name neither canonical nor mapped.
IGNORE_OTHERS = "*"

#: Sidecar keys that steer one reader; a format lists those it reads in its
#: ``sidecar_keys``, and a sidecar may give only keys its clip's formats read.
READER_KEYS = ("person", "individual", "frame_from", "hand_index", "handedness",
               "coordinates", "capture", "frame_offset")

KNOWN_KEYS = frozenset({
    "skeleton", "hand", "fps", "subject", "units", "camera", "bone_lengths", "hand_length",
    "min_confidence", "joint_map", "image", "gap_fill", "lift", *READER_KEYS,
})

#: Where DeepLabCut frame numbers come from: the index column, the image file's number,
#: or the row's position.
FRAME_FROM = ("index", "image_name", "row")

#: How 2D coordinates are given: pixels, [0, 1] or [-1, 1] of the image.
COORDINATES = ("pixels", "normalized", "normalized_signed")

#: ``frame_offset`` value that makes the smallest frame id frame 0.
FIRST_FRAME = "first"


def validate_clip_id(clip_id: str, file: str | Path) -> str:
    """Return ``clip_id`` if it is safe as a file name, else raise :class:`InputError`."""
    if not CLIP_ID_PATTERN.fullmatch(clip_id) or ".." in clip_id:
        raise InputError(
            file,
            f"clip id {quoted(clip_id)} is not allowed: use letters, digits, '.', '_' and '-' "
            "(no path separators, no '..', at most 128 characters)",
            field="clip_id",
        )
    return clip_id


def _number(doc: dict, key: str, path: str, *, positive: bool = True) -> float:
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(path, f"must be a finite number, got {preview(value)}", field=key)
    if positive and value <= 0:
        raise InputError(path, f"must be greater than 0, got {preview(value)}", field=key)
    return float(value)


def _string(doc: dict, key: str, path: str, choices: tuple[str, ...] | None = None) -> str:
    value = doc[key]
    if not isinstance(value, str) or not value:
        raise InputError(path, f"must be a non-empty string, got {preview(value)}", field=key)
    if choices is not None and value not in choices:
        raise InputError(path, f"must be one of {', '.join(choices)}; got {quoted(value)}",
                         field=key)
    return value


def _whole(value: Any, path: str, field: str, *, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise InputError(path, f"must be a whole number from {minimum}, got {preview(value)}",
                         field=field)
    return value


def _fps(doc: dict, path: str) -> float:
    fps = _number(doc, "fps", path)
    if not MIN_FPS <= fps <= MAX_FPS:
        raise InputError(path, f"{fps:g} is not a plausible frame rate ({MIN_FPS:g} to "
                         f"{MAX_FPS:g})", field="fps")
    return fps


def _length(value: float, units: str, valid: tuple[float, float], field: str,
            path: str) -> float:
    """``value`` (``units``) if it lies in the range ``valid`` (metres), else refuse it."""
    low, high = (bound / METERS_PER_UNIT[units] for bound in valid)
    if not low <= value <= high:
        raise InputError(path, f"{value:g} {units} is not a plausible length here (from "
                         f"{low:g} to {high:g} {units}); check the value and the sidecar's "
                         "'units'", field=field)
    return value


def _camera(doc: Any, path: str) -> Camera:
    if not isinstance(doc, dict):
        raise InputError(path, f"must be an object, got {preview(doc)}", field="camera")
    if "model" not in doc:
        raise InputError(path, "needs 'model' (orthographic or pinhole)", field="camera")
    model = _string(doc, "model", path, CAMERA_MODELS)
    if model == "orthographic":
        return Camera()
    missing = [k for k in PINHOLE_KEYS if k not in doc]
    if missing:
        raise InputError(path, f"a pinhole camera needs {', '.join(missing)} (pixels)",
                         field="camera")
    values = {k: _number(doc, k, path, positive=k in ("fx", "fy")) for k in PINHOLE_KEYS}
    return Camera(model="pinhole", **values)


def _mapping(doc: dict, key: str, path: str) -> dict:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise InputError(path, f"must be an object, got {type(value).__name__}", field=key)
    return value


def _joint_map(doc: dict, path: str, skeleton: Skeleton) -> dict[str, str | None]:
    """The validated ``joint_map``: tool name -> canonical joint, or ``None`` to ignore."""
    joint_map = _mapping(doc, "joint_map", path)
    for tool_name, canonical in joint_map.items():
        if canonical is None:
            continue
        if tool_name == IGNORE_OTHERS:
            raise InputError(path, f"maps '{IGNORE_OTHERS}' to {preview(canonical)}; "
                             f"'{IGNORE_OTHERS}' can only be null (ignore every name "
                             "neither canonical nor mapped)", field="joint_map")
        if not isinstance(canonical, str) or canonical not in skeleton.joints:
            raise InputError(path, f"maps {quoted(tool_name)} to {preview(canonical)}, which "
                             f"is not a joint of skeleton '{skeleton.name}' (nor null, to "
                             "ignore the name)", field="joint_map")
    return dict(joint_map)


def _image(doc: dict, path: str) -> tuple[int | None, int | None]:
    if "image" not in doc:
        return None, None
    image = _mapping(doc, "image", path)
    for key in ("width", "height"):
        if key not in image:
            raise InputError(path, f"needs '{key}' (pixels)", field="image")
        value = image[key]
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise InputError(path, f"must be a positive integer, got {preview(value)}",
                             field=f"image.{key}")
        if value > MAX_IMAGE_SIDE:
            raise InputError(path, f"{value} px is not a plausible image side (at most "
                             f"{MAX_IMAGE_SIDE})", field=f"image.{key}")
    return int(image["width"]), int(image["height"])


def _person(doc: dict, path: str) -> tuple[int | None, int | None]:
    """``(index, id)`` of the OpenPose person the sidecar selects, ``None`` for unset."""
    if "person" not in doc:
        return None, None
    value = doc["person"]
    if isinstance(value, dict):
        if set(value) != {"id"}:
            raise InputError(path, 'must be an index or {"id": n}, got ' + preview(value),
                             field="person")
        if value["id"] == -1:
            raise InputError(path, "person id -1 means OpenPose ran without --tracking; "
                             'select by index instead ("person": 0)', field="person.id")
        return None, _whole(value["id"], path, "person.id")
    return _whole(value, path, "person"), None


def _frame_offset(doc: dict, path: str) -> int | str | None:
    value = doc.get("frame_offset")
    if value is None or value == FIRST_FRAME:
        return value
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(path, f'must be a whole number or "{FIRST_FRAME}", got '
                         f"{preview(value)}", field="frame_offset")
    return value


def _reader_options(doc: dict, path: str) -> dict[str, Any]:
    """The validated reader options of :data:`READER_KEYS`, ``None`` where not given."""
    if "hand_index" in doc and "handedness" in doc:
        raise InputError(path, "give hand_index or handedness, not both", field="handedness")
    person, person_id = _person(doc, path)
    capture = doc.get("capture")
    if capture is not None and not isinstance(capture, str):
        capture = str(_whole(capture, path, "capture"))
    return {
        "person": person,
        "person_id": person_id,
        "individual": _string(doc, "individual", path) if "individual" in doc else None,
        "frame_from": _string(doc, "frame_from", path, FRAME_FROM) if "frame_from" in doc
        else None,
        "hand_index": _whole(doc["hand_index"], path, "hand_index") if "hand_index" in doc
        else None,
        "handedness": _string(doc, "handedness", path) if "handedness" in doc else None,
        "coordinates": _string(doc, "coordinates", path, COORDINATES) if "coordinates" in doc
        else None,
        "capture": capture,
        "frame_offset": _frame_offset(doc, path),
    }


def _check_reader_keys(doc: dict, path: str, read_by: Collection[str]) -> None:
    """Refuse reader options that none of the clip's formats (``read_by``) reads."""
    for key in READER_KEYS:
        if key in doc and key not in read_by:
            readers = [fmt.suffix for fmt in FORMATS.values() if key in fmt.sidecar_keys]
            raise InputError(path, f"is not read for this clip's files; only "
                             f"{', '.join(readers)} files read it", field=key)


def parse_sidecar(path: str | Path, clip_id: str | None = None, *,
                  three_d: bool = False, read_by: Collection[str] | None = None) -> ClipSpec:
    """Read and validate a ``<clip_id>.clip.json`` sidecar.

    ``three_d`` says the clip's data file is already 3D (markers): ``camera`` is then
    optional. ``read_by`` are the reader options (:data:`READER_KEYS`) the clip's formats
    read; any other given is refused. ``None`` skips that check (a stored sidecar).

    Raises
    ------
    InputError
        Naming the sidecar, the line of a JSON syntax error, or the key at fault.
    """
    path = str(path)
    if clip_id is None:
        clip_id = Path(path).name.removesuffix(".clip.json")
    validate_clip_id(clip_id, path)
    try:
        text = read_input(Path(path), MAX_SIDECAR_BYTES).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"is not UTF-8 text ({exc.reason})") from None
    return parse_sidecar_text(text, path, clip_id, three_d=three_d, read_by=read_by)


def parse_sidecar_text(text: str, path: str, clip_id: str, *,
                       three_d: bool = False, read_by: Collection[str] | None = None,
                       ) -> ClipSpec:
    """Validate the text of a sidecar; ``path`` is where it came from, for messages.

    Raises
    ------
    InputError
        As :func:`parse_sidecar`.
    """
    if not text.strip():
        raise InputError(path, "is empty; a sidecar needs skeleton, hand, fps, subject, "
                         "units and camera")
    doc = parse_json(text, Path(path))
    if not isinstance(doc, dict):
        raise InputError(path, "must hold a JSON object")
    unknown = sorted(set(doc) - KNOWN_KEYS)
    if unknown:
        raise InputError(path, f"unknown key (known: {', '.join(sorted(KNOWN_KEYS))})",
                         field=unknown[0])
    if read_by is not None:
        _check_reader_keys(doc, path, read_by)
    required = ("skeleton", "hand", "fps", "subject", "units") + (() if three_d else ("camera",))
    for key in required:
        if key not in doc:
            raise InputError(path, "is required", field=key)
    skeleton_name = _string(doc, "skeleton", path)
    try:
        skeleton = load_skeleton(skeleton_name)
    except SkeletonError as exc:
        raise InputError(path, str(exc), field="skeleton") from None
    units = _string(doc, "units", path, tuple(METERS_PER_UNIT))

    bone_lengths = {}
    for joint, length in _mapping(doc, "bone_lengths", path).items():
        if joint not in skeleton.joints or skeleton.parents[skeleton.index(joint)] < 0:
            raise InputError(
                path, f"'{joint}' is not a bone of skeleton '{skeleton.name}' (a bone is "
                "named by its child joint)", field="bone_lengths")
        key = f"bone_lengths.{joint}"
        bone_lengths[joint] = _length(_number({key: length}, key, path), units,
                                      BONE_LENGTH_RANGE_METRES, key, path)

    hand_length = (_length(_number(doc, "hand_length", path), units,
                           HAND_LENGTH_RANGE_METRES, "hand_length", path)
                   if "hand_length" in doc else None)

    min_conf = None
    if "min_confidence" in doc:
        min_conf = _number(doc, "min_confidence", path, positive=False)
        if not 0.0 <= min_conf <= 1.0:
            raise InputError(path, f"must lie in [0, 1], got {min_conf}", field="min_confidence")

    joint_map = _joint_map(doc, path, skeleton)
    width, height = _image(doc, path)
    stages = {}
    for key in ("gap_fill", "lift"):
        stage = _mapping(doc, key, path)
        if stage and not isinstance(stage.get("method"), str):
            raise InputError(path, "needs a 'method' name", field=key)
        stages[key] = dict(stage)

    return ClipSpec(
        clip_id=clip_id,
        path=path,
        skeleton=skeleton.name,
        hand=_string(doc, "hand", path, HANDS),
        fps=_fps(doc, path),
        subject=_string(doc, "subject", path),
        units=units,
        camera=_camera(doc["camera"], path) if "camera" in doc else Camera(model=NO_CAMERA),
        bone_lengths=bone_lengths,
        hand_length=hand_length,
        min_confidence=min_conf,
        joint_map=joint_map,
        image_width=width,
        image_height=height,
        gap_fill=stages["gap_fill"],
        lift=stages["lift"],
        **_reader_options(doc, path),
        raw=json.dumps(doc, sort_keys=True),
    )
