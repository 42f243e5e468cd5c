"""Synthetic clips: a hand model moved by a motion, seen by a camera, with exact truth.

:func:`synthesize_clip` is the one call the demo and the tests use; :func:`render_clip` does
the same for a hand and a motion built by hand; :func:`thesis_clench_clip` reproduces the
thesis's Maya experiment.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from handdb.clip import Camera, Clip, ClipSpec
from handdb.errors import ParameterError, UnknownNameError
from handdb.hand.anatomy import MEAN_HAND_LENGTH_MM
from handdb.hand.model import HandModel, forward_kinematics
from handdb.hand.skeletons import load_skeleton
from handdb.store import tables
from handdb.synthetic.hands import make_hand, thesis_hand
from handdb.synthetic.kinematics import PALM_TO_CAMERA, local_positions, model_poses
from handdb.synthetic.motions import FIST, OPEN, Motion, make_motion
from handdb.synthetic.projection import project_orthographic, project_pinhole

#: Image size (width, height) in pixels of every synthetic camera.
IMAGE_SIZE = (1920, 1080)

#: Focal length of the synthetic pinhole camera, pixels: a wide-angle camera (about 125 deg
#: horizontal field of view at 1920 pixels, like a headset's hand-tracking camera), so that
#: a moving hand 200 mm away stays in the image. The orthographic camera uses the same image
#: footprint at the hand's distance: ``scale = FOCAL_PX / distance``.
FOCAL_PX = 500.0

#: Distance from the camera to the centre of the open hand, mm.
DEFAULT_DISTANCE_MM = 300.0

#: The thesis's experiment: its frame count, and the image scale used for its Maya hand
#: (pixels per Maya unit, a unit taken as 1 cm) and its distance from the camera (cm).
THESIS_FRAMES = 100
THESIS_PIXELS_PER_CM = 40.0
THESIS_DISTANCE_CM = 30.0


@dataclass(frozen=True)
class SyntheticClip:
    """A synthetic clip with exact 3D truth.

    Attributes
    ----------
    motion
        Name of the motion.
    skeleton
        Skeleton preset name.
    joints
        Joint names, ``(J,)``.
    hand
        ``"right"`` or ``"left"``.
    fps
        Frames per second.
    units
        Length unit of ``xyz`` and ``bone_lengths`` (``"mm"``, ``"cm"`` for the thesis).
    xyz
        ``(T, J, 3) float64``: true joint positions, camera frame (x right, y down, z away
        from the camera), ``units``.
    uv
        ``(T, J, 2) float64``: pixel coordinates (with noise, if any was asked for).
    angles
        ``(T, N_ANGLES) float64``: the joint angles, radians.
    bone_lengths
        ``{child joint: length}``, ``units``.
    camera
        The clip sidecar's ``camera`` value: ``{"model": "orthographic"}`` or
        ``{"model": "pinhole", "fx", "fy", "cx", "cy"}`` (pixels).
    image_size
        ``(width, height)``, pixels.
    scale
        Orthographic only: pixels per unit, ``u = scale * x + width / 2``,
        ``v = scale * y + height / 2``; ``None`` for a pinhole camera.
    """

    motion: str
    skeleton: str
    joints: tuple[str, ...]
    hand: str
    fps: float
    units: str
    xyz: np.ndarray
    uv: np.ndarray
    angles: np.ndarray
    bone_lengths: dict[str, float]
    camera: dict[str, Any]
    image_size: tuple[int, int]
    scale: float | None = None

    @property
    def n_frames(self) -> int:
        """Number of frames ``T``."""
        return self.xyz.shape[0]

    def sidecar(self, subject: str = "synthetic") -> dict[str, Any]:
        """Return the content of this clip's ``<clip_id>.clip.json`` sidecar."""
        width, height = self.image_size
        return {
            "skeleton": self.skeleton, "hand": self.hand, "fps": self.fps,
            "subject": subject, "units": self.units, "camera": dict(self.camera),
            "bone_lengths": dict(self.bone_lengths),
            "image": {"width": width, "height": height},
        }

    def as_clip(self, clip_id: str = "synthetic", subject: str = "synthetic") -> Clip:
        """Return this clip as a :class:`~handdb.clip.Clip` with its truth, as if read.

        Every point is observed with confidence 1; ``source_format`` is ``"synthetic"``
        and the content hash covers the pixels and the truth.
        """
        sidecar = self.sidecar(subject)
        spec = ClipSpec(
            clip_id=clip_id, path=f"<synthetic {self.motion}>", skeleton=self.skeleton,
            hand=self.hand, fps=self.fps, subject=subject, units=self.units,
            camera=Camera(**self.camera), bone_lengths=dict(self.bone_lengths),
            image_width=self.image_size[0], image_height=self.image_size[1],
            raw=json.dumps(sidecar, sort_keys=True),
        )
        digest = hashlib.sha256(self.uv.tobytes() + self.xyz.tobytes()).hexdigest()
        return Clip(spec=spec, skeleton=load_skeleton(self.skeleton), uv=self.uv.copy(),
                    confidence=np.ones(self.uv.shape[:2]), truth=self.xyz.copy(),
                    source_format="synthetic", source_files=(), content_hash=digest)

    def truth_table(self, clip_id: str) -> pa.Table:
        """Return this clip's ``truth_3d`` table: one row a frame and joint."""
        n_frames, n_joints = self.xyz.shape[:2]
        flat = self.xyz.reshape(-1, 3)
        return tables.from_columns("truth_3d", {
            "clip_id": clip_id,
            "frame": np.repeat(np.arange(n_frames, dtype=np.int32), n_joints),
            "joint": np.tile(np.array(self.joints), n_frames),
            "joint_index": np.tile(np.arange(n_joints, dtype=np.int32), n_frames),
            "x": flat[:, 0], "y": flat[:, 1], "z": flat[:, 2],
        })


def _check_in_image(uv: np.ndarray, image_size: tuple[int, int]) -> None:
    width, height = image_size
    outside = (uv[..., 0] < 0) | (uv[..., 0] > width) | (uv[..., 1] < 0) | (uv[..., 1] > height)
    if outside.any():
        frame = int(np.argwhere(outside)[0, 0])
        raise ParameterError(
            f"{int(outside.sum())} projected joints fall outside the {width}x{height} image "
            f"(first at frame {frame}); place the hand further from the camera"
        )


def _hand_length(model: HandModel) -> float:
    """Wrist to middle fingertip of the model at rest, its units."""
    rest = forward_kinematics(model, model.rest_pose())
    skeleton = model.skeleton
    return float(np.linalg.norm(rest[skeleton.index("middle_tip")] - rest[skeleton.index("wrist")]))


def hand_centre(model: HandModel) -> np.ndarray:
    """Centre of the space the hand sweeps from open to fist, hand frame, ``(3,) float64``.

    The mean of every joint in the open pose and in the fist: keeping this point on the
    camera axis keeps both the spread fingertips and the curled fist in view.
    """
    return local_positions(model, np.stack([OPEN, FIST])).mean(axis=(0, 1))


def render_clip(
    model: HandModel,
    motion: Motion,
    *,
    camera: str = "orthographic",
    distance: float = DEFAULT_DISTANCE_MM,
    scale: float | None = None,
    focal_px: float = FOCAL_PX,
    image_size: tuple[int, int] = IMAGE_SIZE,
    noise_px: float = 0.0,
    seed: int = 0,
) -> SyntheticClip:
    """Move ``model`` by ``motion`` in front of a camera and project it.

    The hand's centre (:func:`hand_centre`) is placed on the camera axis at ``distance``
    when the motion's root offset is zero; the root
    offsets are scaled by the hand's length. A left hand is the mirror image of the right
    one (camera ``x -> -x``), so its motion is mirrored too.

    Parameters
    ----------
    model
        The hand (its ``units`` are the clip's).
    motion
        Joint angles, wrist rotation and root offsets over ``T`` frames.
    camera
        ``"orthographic"`` or ``"pinhole"``.
    distance
        Camera to the hand's centre, ``model.units``.
    scale
        Orthographic pixels per unit; default ``focal_px / distance``.
    focal_px
        Pinhole focal length, pixels (``fx = fy``).
    image_size
        ``(width, height)``, pixels; the principal point is its centre.
    noise_px
        Standard deviation of Gaussian noise added to the pixel coordinates.
    seed
        Seed of the pixel noise.

    Raises
    ------
    ValueError
        If the camera is unknown or a joint falls outside the image.
    """
    mirror = np.array([-1.0 if model.hand == "left" else 1.0, 1.0, 1.0])
    home = np.array([0.0, 0.0, distance]) - PALM_TO_CAMERA @ hand_centre(model)
    translation = home + _hand_length(model) * motion.root_offset * mirror
    xyz = forward_kinematics(model, model_poses(model, motion.angles, motion.root_rotation,
                                                translation))
    width, height = image_size
    center = (width / 2.0, height / 2.0)
    if camera == "orthographic":
        scale = focal_px / distance if scale is None else scale
        uv = project_orthographic(xyz, scale, center)
        camera_doc: dict[str, Any] = {"model": "orthographic"}
    elif camera == "pinhole":
        uv = project_pinhole(xyz, focal_px, focal_px, *center)
        camera_doc = {"model": "pinhole", "fx": focal_px, "fy": focal_px,
                      "cx": center[0], "cy": center[1]}
        scale = None
    else:
        raise UnknownNameError("camera model", str(camera), ("orthographic", "pinhole"))
    if noise_px > 0:
        uv = uv + np.random.default_rng(seed).normal(0.0, noise_px, uv.shape)
    _check_in_image(uv, image_size)
    return SyntheticClip(
        motion=motion.name, skeleton=model.skeleton.name, joints=model.skeleton.joints,
        hand=model.hand, fps=motion.fps, units=model.units, xyz=xyz, uv=uv,
        angles=motion.angles,
        bone_lengths=dict(zip(model.skeleton.bone_names, map(float, model.bone_lengths),
                              strict=True)),
        camera=camera_doc,
        image_size=(int(width), int(height)), scale=scale,
    )


def synthesize_clip(
    motion: str,
    n_frames: int,
    *,
    skeleton: str = "mediapipe21",
    camera: str = "orthographic",
    seed: int = 0,
    hand: str = "right",
    fps: float = 30.0,
    distance_mm: float = DEFAULT_DISTANCE_MM,
    hand_length_mm: float | None = None,
    noise_px: float = 0.0,
) -> SyntheticClip:
    """Synthesize a clip of ``motion`` by a hand of the population, in mm.

    Parameters
    ----------
    motion
        ``"clench"``, ``"rapid"``, ``"wave"`` or ``"random"``.
    n_frames
        Number of frames ``T``.
    skeleton
        Skeleton preset (``mediapipe21``, ``dhg22``, ``thesis21``).
    camera
        ``"orthographic"`` or ``"pinhole"`` (1920x1080 image, 500 px focal length).
    seed
        Seeds the hand (its size, proportions, palm and annotation conventions,
        :func:`~handdb.hand.population.sample_shape`), the motion and the pixel noise:
        equal seeds give equal clips, different seeds different hands.
    hand
        ``"right"`` or ``"left"`` (the mirror image of the right-hand clip).
    fps
        Frames per second.
    distance_mm
        Camera to the centre of a hand of average length, mm (200-450 keeps the motions in
        the image); a hand of another size is placed in proportion to its length, so that
        it fills the image alike.
    hand_length_mm
        Wrist crease to middle fingertip, mm; drawn with the hand when ``None``.
    noise_px
        Standard deviation of Gaussian pixel noise on ``uv``; ``xyz`` stays exact.
    """
    model = make_hand(skeleton, hand_length_mm, seed=seed, hand=hand)
    size = _hand_length(model) / MEAN_HAND_LENGTH_MM
    return render_clip(
        model, make_motion(motion, n_frames, fps, seed), camera=camera,
        distance=distance_mm * size, noise_px=noise_px, seed=seed,
    )


def thesis_clench_clip(hand: str = "right") -> SyntheticClip:
    """Reproduce the thesis's experiment: its Maya hand clenching, palm to the camera.

    100 frames of ``clench`` on ``thesis21`` with exactly the appendix's segment lengths
    (Maya units, taken as cm), the palm facing the camera and still, seen by an
    orthographic camera at ``THESIS_PIXELS_PER_CM`` pixels per cm (``u = 40 x + 960``,
    ``v = 40 y + 540``). Truth is in cm. The thesis's occlusion pattern (its Table 4.2) is
    not applied here.
    """
    return render_clip(
        thesis_hand(hand), make_motion("clench", THESIS_FRAMES, seed=0),
        camera="orthographic", distance=THESIS_DISTANCE_CM, scale=THESIS_PIXELS_PER_CM,
    )
