"""Synthetic hand motion with known joint rotations, built without handdb's kinematics.

Each finger bends in one plane: its base bone is fixed in the palm; its rest frame has
the bone as Y and the flexion axis as X (across the palm for a finger, the palm normal for
the thumb); the finger's plane is that frame turned about its Z by an abduction angle, and
every bone of the finger is the previous one turned about the plane's X by a positive
flexion angle. Positions come from adding bone vectors; the expected local
rotations are written down from the angles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.export.rotations import rest_positions
from handdb.hand.skeletons import Skeleton, load_skeleton

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


def make_hinge_motion(skeleton: Skeleton, n_frames: int, seed: int = 0,
                      flexion_range: tuple[float, float] = (15.0, 75.0)) -> HingeMotion:
    """Hinge motion whose flexion angles (degrees) stay in ``flexion_range``."""
    rng = np.random.default_rng(seed)
    lengths = bone_lengths_for(skeleton, rng)
    rest = rest_positions(skeleton, lengths)
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


@pytest.fixture(params=["mediapipe21", "thesis21", "dhg22"])
def hinge_motion(request) -> HingeMotion:
    return make_hinge_motion(load_skeleton(request.param), n_frames=60)


@pytest.fixture
def mediapipe_motion() -> HingeMotion:
    return make_hinge_motion(load_skeleton("mediapipe21"), n_frames=40, seed=3)
