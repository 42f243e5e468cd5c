"""Hand motion with known answers, for tests.

:func:`make_hinge_motion`: synthetic hand motion with known joint rotations, built without
handdb's kinematics.

Each finger bends in one plane: its base bone is fixed in the palm; its rest frame has
the bone as Y and the flexion axis as X (across the palm for a finger, the palm normal for
the thumb); the finger's plane is that frame turned about its Z by an abduction angle, and
every bone of the finger is the previous one turned about the plane's X by a positive
flexion angle. Positions come from adding bone vectors; the expected local
rotations are written down from the angles.

:func:`perturbed_hand` and :func:`smooth_poses`: a hand model unlike the template and smooth
motion drawn from the model itself, for the fitting tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from handdb.export.rotations import palm_frame
from handdb.hand.model import N_DOF, HandModel
from handdb.hand.skeletons import Skeleton

#: Directions of the palm root's children in the flat rest hand of the hinge motion, as
#: angles in the palm plane from ``+Y`` (towards the fingers) to ``+X`` (the thumb), degrees.
FLAT_FINGER_ANGLES = {"thumb": 45.0, "index": 12.0, "middle": 0.0, "ring": -12.0,
                      "little": -24.0}
FLAT_PALM_ROLE_ANGLES = {"wrist": 180.0, "palm_center": 0.0}

#: Typical bone lengths of an adult hand by role of the bone's child joint, mm.
LENGTHS_BY_ROLE = {"cmc": 35.0, "mcp": 70.0, "pip": 42.0, "dip": 25.0, "ip": 30.0,
                   "tip": 22.0, "wrist": 40.0, "palm_center": 35.0}


@dataclass(frozen=True)
class HingeMotion:
    skeleton: Skeleton
    xyz: np.ndarray            # (T, J, 3) mm
    bone_lengths: np.ndarray   # (J,) mm
    rotations: np.ndarray      # (T, J, 4) expected local rotations (w, x, y, z)
    fps: float = 30.0


def bone_lengths_for(skeleton: Skeleton, rng: np.random.Generator) -> np.ndarray:
    lengths = np.array([LENGTHS_BY_ROLE.get(r, 0.0) for r in skeleton.roles])
    lengths *= rng.uniform(0.85, 1.15, size=lengths.shape)
    lengths[skeleton.root] = 0.0
    return lengths


def flat_rest(skeleton: Skeleton, lengths: np.ndarray) -> np.ndarray:
    """A flat hand with straight fingers fanned at :data:`FLAT_FINGER_ANGLES`, ``(J, 3)``,
    expressed in its own palm frame (root at the origin)."""
    directions = np.zeros((skeleton.n_joints, 3))
    positions = np.zeros((skeleton.n_joints, 3))
    for parent, child in skeleton.bones:
        if parent == skeleton.root:
            finger, role = skeleton.fingers[child], skeleton.roles[child]
            angle = np.deg2rad(FLAT_FINGER_ANGLES.get(finger,
                                                      FLAT_PALM_ROLE_ANGLES.get(role, 0.0)))
            directions[child] = [np.sin(angle), np.cos(angle), 0.0]
        else:
            directions[child] = directions[parent]
        positions[child] = positions[parent] + lengths[child] * directions[child]
    return positions @ palm_frame(positions[None], skeleton)[0]


def make_hinge_motion(skeleton: Skeleton, n_frames: int, seed: int = 0,
                      flexion_range: tuple[float, float] = (15.0, 75.0)) -> HingeMotion:
    """Hinge motion whose flexion angles (degrees) stay in ``flexion_range``."""
    rng = np.random.default_rng(seed)
    lengths = bone_lengths_for(skeleton, rng)
    rest = flat_rest(skeleton, lengths)
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    palm = Rotation.from_rotvec(rng.normal(size=3) + t * rng.normal(size=3) * 3)
    root_position = rng.normal(scale=50.0, size=3) + t * rng.normal(scale=100.0, size=3)

    J = skeleton.n_joints
    local = np.tile(np.eye(3), (n_frames, J, 1, 1))
    local[:, skeleton.root] = palm.as_matrix()
    xyz = np.empty((n_frames, J, 3))
    xyz[:, skeleton.root] = root_position
    palm_m = palm.as_matrix()
    for parent, child in skeleton.bones:
        if parent != skeleton.root:
            continue
        xyz[:, child] = root_position + np.einsum("tij,j->ti", palm_m, rest[child])
        chain = [child]
        while len(skeleton.children(chain[-1])) == 1:
            chain.append(int(skeleton.children(chain[-1])[0]))
        d = (rest[child] - rest[parent]) / lengths[child]
        normal = np.array([0, 0, 1.0])
        if skeleton.fingers[child] == "thumb":      # the thumb bends about the palm normal
            rest_frame = np.stack([normal, d, np.cross(normal, d)], axis=-1)
        else:
            rest_frame = np.stack([np.cross(d, normal), d, normal], axis=-1)
        abduction = Rotation.from_rotvec(np.outer(np.sin(6 * t[:, 0] + rng.uniform(0, 6)),
                                                  [0, 0, np.deg2rad(15)])).as_matrix()
        plane = rest_frame @ abduction                                  # (T, 3, 3)
        flexions = np.deg2rad(flexion_range[0] + (flexion_range[1] - flexion_range[0])
                              * 0.5 * (1 + np.sin(4 * t + rng.uniform(0, 6, size=len(chain) - 1))))
        if len(chain) > 1:
            local[:, child] = plane
        bend = np.zeros(n_frames)
        for k in range(1, len(chain)):
            bend = bend + flexions[:, k - 1]
            if k > 1:
                local[:, chain[k - 1]] = Rotation.from_rotvec(
                    np.outer(flexions[:, k - 1], [1.0, 0, 0])).as_matrix()
            else:
                local[:, chain[0]] = plane @ Rotation.from_rotvec(
                    np.outer(flexions[:, 0], [1.0, 0, 0])).as_matrix()
            direction = palm_m @ plane @ Rotation.from_rotvec(
                np.outer(bend, [1.0, 0, 0])).as_matrix() @ np.array([0, 1.0, 0])
            xyz[:, chain[k]] = xyz[:, chain[k - 1]] + lengths[chain[k]] * direction
    quats = Rotation.from_matrix(local.reshape(-1, 3, 3)).as_quat(scalar_first=True)
    return HingeMotion(skeleton, xyz, lengths, quats.reshape(n_frames, J, 4))



def perturbed_hand(model: HandModel, seed: int) -> HandModel:
    """A hand of another size (±10 %), bones varying ±5 % more, and another palm shape."""
    rng = np.random.default_rng(seed)
    size = rng.choice([0.9, 1.1])
    lengths = model.bone_lengths * size * rng.uniform(0.95, 1.05, model.bone_lengths.shape)
    directions = model.rest_directions.copy()
    directions[model.palm_joints] += rng.normal(0.0, 0.04, (len(model.palm_joints), 3))
    return model.with_geometry(lengths, directions)


def noisy_markers(truth: np.ndarray, *, noise: float, missing_share: float, seed: int
                  ) -> np.ndarray:
    """``(T, J, 3)`` markers: ``truth`` plus Gaussian noise, a share of them missing (NaN).

    ``noise`` is the noise's standard deviation in ``truth``'s unit; each marker is missing
    with probability ``missing_share``; both drawn from ``seed``.
    """
    rng = np.random.default_rng(seed)
    markers = truth + rng.normal(0.0, noise, truth.shape)
    markers[rng.random(truth.shape[:2]) < missing_share] = np.nan
    return markers


def smooth_poses(model: HandModel, n_frames: int, seed: int) -> np.ndarray:
    """``(n_frames, 33)`` poses moving smoothly inside the joint limits (mm, rad)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames)[:, None]
    lower = np.maximum(model.lower, -np.pi / 3)
    upper = np.minimum(model.upper, np.pi / 3)
    middle, half = (upper + lower) / 2, (upper - lower) / 2
    phase = rng.uniform(0, 2 * np.pi, N_DOF)
    speed = rng.uniform(0.03, 0.12, N_DOF)
    poses = middle + 0.6 * half * np.sin(speed * t + phase)
    poses[:, :3] = [0.0, 0.0, 400.0] + 30.0 * np.sin(0.05 * t + phase[:3])
    poses[:, 3:6] = [0.3, -0.2, 0.4] + 0.3 * np.sin(0.04 * t + phase[3:6])
    return poses
