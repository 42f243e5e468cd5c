"""The clip: one hand recording as dense arrays, with the sidecar that says what they mean.

:class:`Clip` is the one clip type of handdb: readers make it (:mod:`handdb.ingest`), the
stages read it, the store rebuilds it from its tables. :class:`ClipSpec` is its validated
sidecar (:func:`handdb.ingest.sidecar.parse_sidecar`), :class:`Camera` the camera of its
2D tracks.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from handdb.hand.skeletons import Skeleton

#: Metres per unit of each length unit a sidecar may name.
METERS_PER_UNIT: dict[str, float] = {"mm": 0.001, "cm": 0.01, "m": 1.0, "in": 0.0254}

#: Points whose confidence is below this count as missing, unless the sidecar or the
#: clip's format (:data:`FORMAT_MIN_CONFIDENCE`) says.
DEFAULT_MIN_CONFIDENCE = 0.5

#: The confidence below which a format's own tool counts a point as not found, by
#: ``source_format``, where it is not :data:`DEFAULT_MIN_CONFIDENCE`. OpenPose's hand
#: keypoint detector reports much lower confidences than its body detector: OpenPose draws
#: a hand keypoint from 0.2 on (``hand_render_threshold``, default 0.2, in
#: ``include/openpose/flags.hpp``, against 0.05 for the body and 0.4 for the face).
FORMAT_MIN_CONFIDENCE: dict[str, float] = {"openpose": 0.2}

HANDS = ("left", "right")
CAMERA_MODELS = ("orthographic", "pinhole")
#: The camera model of clips whose data is already 3D (marker clips).
NO_CAMERA = "none"

#: How a clip's frames were sampled (:attr:`Clip.sampling`): ``"video"``, consecutive
#: samples of one recording, in time order; ``"images"``, independent images (DeepLabCut's
#: labelled data), whose order says nothing, so that every stage treats each frame on its
#: own (no interpolation, smoothing or temporal model across frames).
VIDEO, IMAGES = "video", "images"
SAMPLINGS = (VIDEO, IMAGES)


def finite_points(points: np.ndarray) -> np.ndarray:
    """Whether each point has every coordinate finite.

    Parameters
    ----------
    points
        ``(..., C) float``: points of ``C`` coordinates (``u, v`` pixels; ``x, y, z``).

    Returns
    -------
    numpy.ndarray
        ``(...) bool``. The same as ``np.isfinite(points).all(axis=-1)``, which numpy
        reduces point by point over the short last axis, about 30 times slower than
        combining its ``C`` slices as this does.
    """
    present = np.ones(points.shape[:-1], dtype=bool)
    for k in range(points.shape[-1]):
        present &= np.isfinite(points[..., k])
    return present


@dataclass(frozen=True)
class Camera:
    """The camera a clip's 2D tracks were seen through.

    ``model`` is ``"orthographic"`` (scaled orthographic, scale unknown) or ``"pinhole"``
    with focal lengths ``fx, fy`` and principal point ``cx, cy`` in pixels; ``"none"`` for
    clips whose data is already 3D.
    """

    model: str = "orthographic"
    fx: float | None = None
    fy: float | None = None
    cx: float | None = None
    cy: float | None = None


@dataclass(frozen=True)
class ClipSpec:
    """The validated content of a clip's sidecar.

    ``joint_map`` maps a tool's names to canonical joint names, or to ``None`` for names
    that are known and ignored; the key ``"*"`` (always ``None``) ignores every name that
    is neither canonical nor a key. The attributes after ``lift`` are reader options, each
    ``None`` when the sidecar does not give it (the reader's default then applies):

    ``person``, ``person_id``
        OpenPose: the index in ``people`` (``"person": n``) or the tracked person id
        (``"person": {"id": n}``).
    ``individual``
        DeepLabCut multi-animal files: the individual whose columns are read.
    ``frame_from``
        DeepLabCut: ``"index"``, ``"image_name"`` or ``"row"``, where frame numbers come
        from.
    ``hand_index``, ``handedness``
        MediaPipe: the hand by its position in MediaPipe's list, or by its label.
    ``coordinates``
        OpenPose and MediaPipe: ``"pixels"``, ``"normalized"`` ([0, 1] of the image) or
        ``"normalized_signed"`` ([-1, 1], OpenPose only).
    ``capture``
        InterHand2.6M: the capture id.
    ``frame_offset``
        InterHand2.6M: an integer subtracted from the frame ids, or ``"first"``.
    """

    clip_id: str
    path: str
    skeleton: str
    hand: str
    fps: float
    subject: str
    units: str
    camera: Camera
    bone_lengths: dict[str, float] = field(default_factory=dict)
    hand_length: float | None = None
    min_confidence: float | None = None
    joint_map: dict[str, str | None] = field(default_factory=dict)
    image_width: int | None = None
    image_height: int | None = None
    gap_fill: dict[str, Any] = field(default_factory=dict)
    lift: dict[str, Any] = field(default_factory=dict)
    person: int | None = None
    person_id: int | None = None
    individual: str | None = None
    frame_from: str | None = None
    hand_index: int | None = None
    handedness: str | None = None
    coordinates: str | None = None
    capture: str | None = None
    frame_offset: int | str | None = None
    raw: str = "{}"

    @property
    def meters_per_unit(self) -> float:
        """Metres in one of the clip's length units."""
        return METERS_PER_UNIT[self.units]


@dataclass(frozen=True)
class Clip:
    """One clip's 2D tracks (and ground truth, if any) as dense arrays.

    Attributes
    ----------
    spec
        The sidecar.
    skeleton
        The clip's skeleton; the joint axis of every array follows its order.
    uv
        ``(T, J, 2) float64``, pixels (x right, y down); NaN where the source has no point.
    confidence
        ``(T, J) float64`` in [0, 1]; NaN where the format carries no confidence.
    truth
        ``(T, J, 3) float64`` in ``spec.units``, camera frame; NaN where absent; ``None``
        for clips without ground truth.
    markers
        ``(T, J, 3) float64`` 3D marker positions in ``spec.units``, NaN where a marker is
        missing, for clips whose data file is 3D (``uv`` is then all NaN); else ``None``.
    source_format
        Name of the reader that read the tracks (``tracks_csv``, ``openpose``, ...).
    source_files
        Every input file of the clip, sidecar first.
    content_hash
        SHA-256 over the clip's input files; the clip's identity in the database.
    sampling
        ``"video"`` (the default) or ``"images"``: see :data:`SAMPLINGS`; the reader
        decides it, the ``clips`` table stores it.
    """

    spec: ClipSpec
    skeleton: Skeleton
    uv: np.ndarray
    confidence: np.ndarray
    truth: np.ndarray | None
    source_format: str
    source_files: tuple[str, ...]
    content_hash: str
    markers: np.ndarray | None = None
    sampling: str = VIDEO

    def __post_init__(self) -> None:
        if self.sampling not in SAMPLINGS:
            raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, "
                             f"got {self.sampling!r}")

    @property
    def clip_id(self) -> str:
        """The clip's id."""
        return self.spec.clip_id

    @property
    def n_frames(self) -> int:
        """Number of frames ``T``."""
        return int(self.uv.shape[0])

    @property
    def observed(self) -> np.ndarray:
        """``(T, J) bool``: the point is present and not below ``min_confidence``.

        For marker clips: the marker is present.
        """
        if self.markers is not None:
            return finite_points(self.markers)
        present = finite_points(self.uv)
        conf = self.confidence
        confident = np.isnan(conf) | (conf >= self.min_confidence)
        return present & confident

    @property
    def min_confidence(self) -> float:
        """The confidence below which points count as missing.

        The sidecar's, else the format's (:data:`FORMAT_MIN_CONFIDENCE`), else
        :data:`DEFAULT_MIN_CONFIDENCE`.
        """
        if self.spec.min_confidence is not None:
            return self.spec.min_confidence
        return FORMAT_MIN_CONFIDENCE.get(self.source_format, DEFAULT_MIN_CONFIDENCE)
