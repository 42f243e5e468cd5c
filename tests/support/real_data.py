"""Real hand captures with 3D truth, seen through cameras, and what a lift gets wrong.

- :func:`load_dhg`: the DHG capture (RealSense SDK skeleton, 95 frames, ``dhg22``).
- :func:`load_interhand`: the InterHand2.6M sample's hands with all 21 joints valid, one
  frame each, as ``mediapipe21`` (its order per hand: thumb4..thumb1, forefinger4..1,
  middle4..1, ring4..1, pinky4..1, wrist; the left hand's joints follow the right's).
- :func:`camera_view`, :func:`pseudo_clip`, :func:`project`: a capture turned to face a
  camera some way, put at a distance, optionally wobbled into a clip, and projected
  orthographically or through a pinhole, with pixel noise.
- :class:`Errors`: per-joint and per-bone errors pooled over views.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.clip import Camera
from handdb.hand.skeletons import FINGERS, Skeleton, frame_bone_lengths, load_skeleton

#: InterHand2.6M's 21 joints of one hand, in its order (tip to base per finger, wrist last).
INTERHAND_ORDER = (
    "thumb_tip", "thumb_ip", "thumb_mcp", "thumb_cmc", "index_tip", "index_dip", "index_pip",
    "index_mcp", "middle_tip", "middle_dip", "middle_pip", "middle_mcp", "ring_tip",
    "ring_dip", "ring_pip", "ring_mcp", "little_tip", "little_dip", "little_pip",
    "little_mcp", "wrist",
)

#: Pinhole focal length and principal point of the test camera, pixels; the orthographic
#: camera has the same footprint at the hand's mean distance (``scale = focal / depth``).
FOCAL_PX = 500.0
PRINCIPAL_POINT = np.array([320.0, 240.0])

#: Distances of the hand's centre from the camera, mm.
DISTANCE_MM = (400.0, 600.0)

#: Pseudo-clips: a still pose turned by two sinusoidal rotations about random axes, of
#: this amplitude (degrees), over this many frames.
WOBBLE_DEG = 25.0
PSEUDO_FRAMES = 60

#: Bones whose true depth span is below this are left out of the sign accuracy, mm (as in
#: :data:`handdb.validation.depth.SIGN_THRESHOLD_M`).
SIGN_THRESHOLD_MM = 5.0


@dataclass(frozen=True)
class Capture:
    """A real capture: ``xyz`` ``(T, J, 3)`` mm in its own frame."""

    name: str
    skeleton: str
    hand: str
    xyz: np.ndarray


def load_dhg(path: Path) -> Capture:
    """The DHG capture in mm; its joint order is ``dhg22``'s."""
    return Capture("dhg", "dhg22", "right", np.loadtxt(path).reshape(-1, 22, 3) * 1000.0)


def load_interhand(path: Path) -> list[Capture]:
    """Every hand of the InterHand2.6M sample with all 21 joints valid, one frame each."""
    skeleton = load_skeleton("mediapipe21")
    order = [INTERHAND_ORDER.index(joint) for joint in skeleton.joints]
    captures = []
    for capture, frames in json.loads(path.read_text()).items():
        for frame, record in frames.items():
            world = np.asarray(record["world_coord"], dtype=np.float64)
            valid = np.asarray(record["joint_valid"]).ravel() > 0
            for hand, first in (("right", 0), ("left", 21)):
                if valid[first:first + 21].all():
                    points = world[first:first + 21][order]
                    captures.append(Capture(f"interhand-{capture}-{frame}-{hand}",
                                            "mediapipe21", hand, points[None]))
    return captures


def median_bone_lengths(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Each bone's median length over the frames, ``(J,)`` (NaN at the root)."""
    return np.median(frame_bone_lengths(xyz, skeleton), axis=0)


def view_rotations(n_views: int, seed: int) -> np.ndarray:
    """``n_views`` rotations uniform over SO(3), fixed by ``seed``, ``(n, 3, 3)``."""
    return Rotation.random(n_views, random_state=seed).as_matrix().reshape(n_views, 3, 3)


def camera_view(xyz: np.ndarray, rotation: np.ndarray, distance: float) -> np.ndarray:
    """A capture turned about its mean centre and put ``distance`` mm in front, ``(T, J, 3)``."""
    centre = xyz.reshape(-1, 3).mean(axis=0)
    return (xyz - centre) @ rotation.T + np.array([0.0, 0.0, distance])


def pseudo_clip(pose: np.ndarray, rng: np.random.Generator,
                n_frames: int = PSEUDO_FRAMES) -> np.ndarray:
    """A still pose ``(J, 3)`` wobbling as a rigid body, ``(T, J, 3)``.

    Two rotations of :data:`WOBBLE_DEG` amplitude about random axes, one at the clip's
    frequency and one at twice it, about the pose's centre: a real hand's shape under
    synthetic motion.
    """
    axes = rng.normal(size=(2, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    phase = np.linspace(0.0, 2.0 * np.pi, n_frames)
    amplitude = np.radians(WOBBLE_DEG)
    turn = (Rotation.from_rotvec(axes[0] * (amplitude * np.sin(phase))[:, None])
            * Rotation.from_rotvec(axes[1] * (amplitude * np.sin(2 * phase + 1.0))[:, None]))
    centre = pose.mean(axis=0)
    return np.einsum("tij,kj->tki", turn.as_matrix(), pose - centre) + centre


def project(xyz: np.ndarray, model: str, noise_px: float = 0.0,
            rng: np.random.Generator | None = None) -> tuple[np.ndarray, Camera]:
    """Image points of camera-frame points ``(T, J, 3)`` mm, and the camera.

    Orthographic: ``uv = s · (x, y)`` with ``s = FOCAL_PX / mean depth``; pinhole:
    ``FOCAL_PX`` and :data:`PRINCIPAL_POINT`. Gaussian noise of ``noise_px`` per
    coordinate (``rng`` required when positive).
    """
    if model == "orthographic":
        uv, camera = xyz[..., :2] * (FOCAL_PX / xyz[..., 2].mean()), Camera()
    else:
        uv = xyz[..., :2] / xyz[..., 2:] * FOCAL_PX + PRINCIPAL_POINT
        camera = Camera("pinhole", FOCAL_PX, FOCAL_PX, *PRINCIPAL_POINT)
    if noise_px > 0:
        if rng is None:
            raise ValueError("pixel noise needs a random generator")
        uv = uv + rng.normal(scale=noise_px, size=uv.shape)
    return uv, camera


def procrustes_errors(truth: np.ndarray, estimate: np.ndarray) -> np.ndarray:
    """Mean joint error of each frame after the best similarity transform, ``(T,)`` mm.

    Frames with fewer than four estimated joints are NaN.
    """
    errors = np.full(len(truth), np.nan)
    for t in range(len(truth)):
        ok = np.isfinite(estimate[t]).all(axis=1)
        if ok.sum() < 4:
            continue
        a, b = truth[t, ok] - truth[t, ok].mean(0), estimate[t, ok] - estimate[t, ok].mean(0)
        u, s, vt = np.linalg.svd(b.T @ a)
        flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
        rotation = u @ flip @ vt
        scale = float(np.sum(s * np.diag(flip)) / np.sum(b**2))
        errors[t] = float(np.mean(np.linalg.norm(scale * b @ rotation - a, axis=1)))
    return errors


@dataclass
class Errors:
    """Errors of one method pooled over views and captures of one skeleton.

    Depth errors are root-relative; a bone's sign counts where its true depth span is at
    least :data:`SIGN_THRESHOLD_MM`, and an estimated span of exactly 0 counts as wrong.
    """

    skeleton: Skeleton
    dz: np.ndarray = field(init=False)
    position: np.ndarray = field(init=False)
    n: np.ndarray = field(init=False)
    agree: np.ndarray = field(init=False)
    n_sign: np.ndarray = field(init=False)
    procrustes: list = field(init=False, default_factory=list)

    def __post_init__(self) -> None:
        """Start every sum at zero."""
        n_joints = self.skeleton.n_joints
        self.dz, self.position, self.n = (np.zeros(n_joints) for _ in range(3))
        self.agree, self.n_sign = np.zeros(n_joints), np.zeros(n_joints)

    def add(self, truth: np.ndarray, estimate: np.ndarray) -> None:
        """Pool one clip: ``(T, J, 3)`` truth and estimate, mm, camera frame."""
        root = self.skeleton.root
        true, est = truth - truth[:, root:root + 1], estimate - estimate[:, root:root + 1]
        dz = np.abs(est[..., 2] - true[..., 2])
        self.dz += np.nansum(dz, axis=0)
        self.position += np.nansum(np.linalg.norm(est - true, axis=-1), axis=0)
        self.n += np.isfinite(dz).sum(axis=0)
        parents = np.where(self.skeleton.parents < 0, root, self.skeleton.parents)
        true_bone = truth[..., 2] - truth[:, parents, 2]
        est_bone = estimate[..., 2] - estimate[:, parents, 2]
        counted = (np.abs(true_bone) >= SIGN_THRESHOLD_MM) & np.isfinite(est_bone)
        counted[:, root] = False
        self.agree += ((np.sign(true_bone) == np.sign(est_bone)) & counted).sum(axis=0)
        self.n_sign += counted.sum(axis=0)
        self.procrustes.append(procrustes_errors(truth, estimate))

    def groups(self) -> dict[str, np.ndarray]:
        """Joints of ``all`` and of each finger (a bone belongs to its child's finger)."""
        fingers = np.array(self.skeleton.fingers)
        return {"all": np.arange(self.skeleton.n_joints),
                **{f: np.flatnonzero(fingers == f) for f in FINGERS}}

    def summary(self) -> dict[str, dict[str, float]]:
        """Per group: mean ``dz`` and ``mpjpe`` (mm), ``sign`` accuracy; ``all`` also
        ``pa_mpjpe``."""
        out = {}
        for name, joints in self.groups().items():
            n, n_sign = self.n[joints].sum(), self.n_sign[joints].sum()
            out[name] = {"dz": float(self.dz[joints].sum() / n),
                         "mpjpe": float(self.position[joints].sum() / n),
                         "sign": float(self.agree[joints].sum() / n_sign) if n_sign else np.nan}
        out["all"]["pa_mpjpe"] = float(np.nanmean(np.concatenate(self.procrustes)))
        return out

    def bone_signs(self) -> dict[str, float]:
        """Sign accuracy of every bone counted at least once, by ``parent->child``."""
        names = self.skeleton.joints
        return {f"{names[self.skeleton.parents[j]]}->{names[j]}": float(self.agree[j]
                                                                        / self.n_sign[j])
                for j in range(self.skeleton.n_joints) if self.n_sign[j] > 0}
