"""MediaPipe world landmarks as 3D markers, ``<clip_id>.mediapipe-world.json``.

The document is that of :mod:`handdb.ingest.mediapipe` (legacy entries with
``world_landmarks``, or Tasks ``HandLandmarkerResult`` entries with
``hand_world_landmarks``); the clip is its world landmarks: metric 3D points in metres,
origin at the hand's geometric centre, axes those of MediaPipe's camera (x right, y down,
z away). They are read as a 3D marker clip (kind ``markers``, no camera needed) in the
sidecar's units. The hand is chosen as for image landmarks (``hand_index`` or
``handedness``); a frame without world landmarks has every marker missing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from handdb.clip import METERS_PER_UNIT, ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.mediapipe import HAND_SKELETON, read_hands
from handdb.ingest.observations import Positions, resolve_names, single_file_rows
from handdb.ingest.registry import MARKERS_KIND, InputFormat

#: The unit of MediaPipe's world landmarks.
WORLD_UNITS = "m"


def read(path: str | Path, spec: ClipSpec, skeleton: Skeleton) -> Positions:
    """Read the world landmarks of a MediaPipe JSON document as 3D markers (clip units).

    Raises
    ------
    InputError
        As :func:`handdb.ingest.mediapipe.read`, or if no frame has world landmarks.
    """
    path = Path(path)
    _, hands, n_frames = read_hands(path, spec)
    world = {frame: hand.world for frame, hand in sorted(hands.items())
             if hand.world is not None}
    if not world:
        raise InputError(path, "holds no world landmarks (hand_world_landmarks or "
                         "world_landmarks); read image landmarks as <clip_id>.mediapipe.json",
                         field="hand_world_landmarks")
    hand = load_skeleton(HAND_SKELETON)
    joints = resolve_names(hand.joints, spec, skeleton, path,
                           lambda k: (None, "hand_world_landmarks"), fixed=True)
    kept = np.flatnonzero(joints >= 0)
    scale = METERS_PER_UNIT[WORLD_UNITS] / spec.meters_per_unit
    points = np.array(list(world.values()))[:, kept] * scale
    source, files = single_file_rows(path, points.shape[0] * kept.size)
    return Positions(
        frame=np.repeat(np.array(list(world), dtype=np.int64), kept.size),
        joint=np.tile(joints[kept], len(world)),
        xyz=points.reshape(-1, 3),
        line=np.zeros(source.size, dtype=np.int64),
        source=source,
        files=files,
        skeleton=skeleton,
        n_frames=n_frames,
        names=frozenset(hand.joints),
        fields=dict.fromkeys("xyz", "hand_world_landmarks[{joint}]"),
    )


FORMAT = InputFormat(name="mediapipe_world", suffix=".mediapipe-world.json", kind=MARKERS_KIND,
                     read=read, sidecar_keys=("hand_index", "handedness"))
