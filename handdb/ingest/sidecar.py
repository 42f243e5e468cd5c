"""The sidecar ``<clip_id>.clip.json``: how to read a clip's track file, what it means.

The sidecar says how to read the clip's track file and what the numbers mean::

    {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
     "units": "mm", "camera": {"model": "orthographic"}}

``camera`` may instead be ``{"model": "pinhole", "fx": .., "fy": .., "cx": .., "cy": ..}``
(pixels); a clip whose data file is already 3D (markers) needs no camera. Optional keys:
``bone_lengths`` (child joint -> length in ``units``), ``min_confidence`` (default 0.5),
``joint_map`` (tool names -> canonical names), ``image`` (``{"width": W, "height": H}``,
pixels; needed for normalised coordinates), ``gap_fill`` and ``lift``
(``{"method": NAME, ...parameters}``).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

from handdb.clip import (
    CAMERA_MODELS,
    DEFAULT_MIN_CONFIDENCE,
    HANDS,
    METERS_PER_UNIT,
    NO_CAMERA,
    Camera,
    ClipSpec,
)
from handdb.errors import InputError, SkeletonError
from handdb.hand.skeletons import load_skeleton

#: A clip id: letters, digits, ``.``, ``_``, ``-``; no path separators, not ``..``.
CLIP_ID_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")

PINHOLE_KEYS = ("fx", "fy", "cx", "cy")
KNOWN_KEYS = frozenset({
    "skeleton", "hand", "fps", "subject", "units", "camera", "bone_lengths", "hand_length",
    "min_confidence", "joint_map", "image", "gap_fill", "lift",
})

def validate_clip_id(clip_id: str, file: str | Path) -> str:
    """Return ``clip_id`` if it is safe as a file name, else raise :class:`InputError`."""
    if not CLIP_ID_PATTERN.match(clip_id) or ".." in clip_id:
        raise InputError(
            file,
            f"clip id '{clip_id}' is not allowed: use letters, digits, '.', '_' and '-' "
            "(no path separators, no '..', at most 128 characters)",
            field="clip_id",
        )
    return clip_id


def _number(doc: dict, key: str, path: str, *, positive: bool = True) -> float:
    value = doc[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(path, f"must be a finite number, got {value!r}", field=key)
    if positive and value <= 0:
        raise InputError(path, f"must be greater than 0, got {value!r}", field=key)
    return float(value)


def _string(doc: dict, key: str, path: str, choices: tuple[str, ...] | None = None) -> str:
    value = doc[key]
    if not isinstance(value, str) or not value:
        raise InputError(path, f"must be a non-empty string, got {value!r}", field=key)
    if choices is not None and value not in choices:
        raise InputError(path, f"must be one of {', '.join(choices)}; got '{value}'", field=key)
    return value


def _camera(doc: Any, path: str) -> Camera:
    if not isinstance(doc, dict):
        raise InputError(path, f"must be an object, got {doc!r}", field="camera")
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


def parse_sidecar(path: str | Path, clip_id: str | None = None, *,
                  three_d: bool = False) -> ClipSpec:
    """Read and validate a ``<clip_id>.clip.json`` sidecar.

    ``three_d`` says the clip's data file is already 3D (markers): ``camera`` is then
    optional.

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
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"is not UTF-8 text ({exc.reason})") from None
    return parse_sidecar_text(text, path, clip_id, three_d=three_d)


def parse_sidecar_text(text: str, path: str, clip_id: str, *,
                       three_d: bool = False) -> ClipSpec:
    """Validate the text of a sidecar; ``path`` is where it came from, for messages.

    Raises
    ------
    InputError
        As :func:`parse_sidecar`.
    """
    if not text.strip():
        raise InputError(path, "is empty; a sidecar needs skeleton, hand, fps, subject, "
                         "units and camera")
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(path, f"is not valid JSON: {exc.msg}", line=exc.lineno) from None
    if not isinstance(doc, dict):
        raise InputError(path, "must hold a JSON object")
    unknown = sorted(set(doc) - KNOWN_KEYS)
    if unknown:
        raise InputError(path, f"unknown key (known: {', '.join(sorted(KNOWN_KEYS))})",
                         field=unknown[0])
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
        bone_lengths[joint] = _number({f"bone_lengths.{joint}": length},
                                      f"bone_lengths.{joint}", path)

    hand_length = _number(doc, "hand_length", path) if "hand_length" in doc else None

    min_conf = DEFAULT_MIN_CONFIDENCE
    if "min_confidence" in doc:
        min_conf = _number(doc, "min_confidence", path, positive=False)
        if not 0.0 <= min_conf <= 1.0:
            raise InputError(path, f"must lie in [0, 1], got {min_conf}", field="min_confidence")

    joint_map = _mapping(doc, "joint_map", path)
    for tool_name, canonical in joint_map.items():
        if not isinstance(canonical, str) or canonical not in skeleton.joints:
            raise InputError(path, f"maps '{tool_name}' to '{canonical}', which is not a joint "
                             f"of skeleton '{skeleton.name}'", field="joint_map")

    width = height = None
    if "image" in doc:
        image = _mapping(doc, "image", path)
        for key in ("width", "height"):
            if key not in image:
                raise InputError(path, f"needs '{key}' (pixels)", field="image")
            value = image[key]
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                raise InputError(path, f"must be a positive integer, got {value!r}",
                                 field=f"image.{key}")
        width, height = int(image["width"]), int(image["height"])

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
        fps=_number(doc, "fps", path),
        subject=_string(doc, "subject", path),
        units=units,
        camera=_camera(doc["camera"], path) if "camera" in doc else Camera(model=NO_CAMERA),
        bone_lengths=bone_lengths,
        hand_length=hand_length,
        min_confidence=min_conf,
        joint_map={str(k): str(v) for k, v in joint_map.items()},
        image_width=width,
        image_height=height,
        gap_fill=stages["gap_fill"],
        lift=stages["lift"],
        raw=json.dumps(doc, sort_keys=True),
    )
