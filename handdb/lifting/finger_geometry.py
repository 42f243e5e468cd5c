"""Candidate 3D bones of every finger sign state, seen orthographically or through a pinhole.

The hand prior (:mod:`handdb.lifting.hand_prior`) scores each finger's eight sign states
under each of the palm's two tilt states. What it needs is, per palm state, where the palm
is (the wrist, the index and little MCP joints and the joint each finger hangs from) and,
per finger state, the three bone vectors below the palm. Through a pinhole a bone's vector
depends on every sign above it, since the parent's depth decides where along its ray the
child can lie. Orthographically it depends on its own sign only, ``(dx, dy, ±|dZ|)``, and
palm state 1 is state 0's mirror image, so no candidates are built there:
:func:`handdb.lifting.hand_prior.score_mirrored_fingers` takes them from the image.
Sign axes are ordered like :data:`handdb.lifting.hand_prior.SIGN_STATES`: index 0 is the
positive (deeper) choice.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from handdb.compiled import kernel
from handdb.hand.layout import HandLayout


@dataclass(frozen=True)
class FingerCandidates:
    """Palm anchors and candidate finger bones, per palm state and finger sign state.

    Attributes
    ----------
    anchors
        ``(T, 2, 3 + F, 3) float64``, clip units: wrist, index MCP, little MCP, then the
        joint each finger hangs from, in palm state 0 and 1.
    bones
        Three arrays broadcastable to ``(T, 2, F, 2, 2, 2, 3)``: the vector of each
        finger's first, second and third bone below the palm for each sign of bone 1, 2,
        3 (axes 3, 4, 5).
    joints
        Three arrays ``(T, 2, F, 2, 3)``, ``(T, 2, F, 2, 2, 3)``, ``(T, 2, F, 2, 2, 2, 3)``:
        where the chain joints lie (``None`` when not known).
    palm
        ``(T, 2, J, 3) float64``: every joint of the palm in each palm state (``None`` when
        not known).
    """

    anchors: np.ndarray
    bones: tuple[np.ndarray, np.ndarray, np.ndarray]
    joints: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    palm: np.ndarray | None = None


def anchor_joints(layout: HandLayout) -> np.ndarray:
    """Joints of :attr:`FingerCandidates.anchors`, ``(3 + F,) int64``."""
    return np.concatenate([[layout.wrist, layout.index_mcp, layout.little_mcp],
                           layout.chain_bases])


def perspective_candidates(rays: np.ndarray, palm_xyz: np.ndarray, bone_lengths: np.ndarray,
                           layout: HandLayout) -> FingerCandidates:
    """Candidates through a pinhole camera.

    Parameters
    ----------
    rays
        ``(T, J, 3) float64`` from :func:`handdb.lifting.pinhole.camera_rays`.
    palm_xyz
        ``(T, 2, J, 3) float64``, clip units: the palm's joints in palm state 0 and 1
        (other joints: ignored).
    bone_lengths
        ``(J,) float64``, clip units.
    layout
        The skeleton's palm and fingers.
    """
    n_frames, n_fingers = len(rays), len(layout.fingers)
    first = np.empty((n_frames, 2, n_fingers, 2, 3))
    second = np.empty((n_frames, 2, n_fingers, 2, 2, 3))
    third = np.empty((n_frames, 2, n_fingers, 2, 2, 2, 3))
    vectors = (np.empty(first.shape), np.empty(second.shape), np.empty(third.shape))
    _chain_candidates(rays, palm_xyz, layout.chains, layout.chain_bases,
                      bone_lengths[layout.chains], first, second, third, *vectors)
    bones = (vectors[0][..., :, None, None, :], vectors[1][..., None, :], vectors[2])
    return FingerCandidates(anchors=palm_xyz[:, :, anchor_joints(layout)], bones=bones,
                            joints=(first, second, third), palm=palm_xyz)


@kernel
def _ray_root(rays, t, joint, ox, oy, oz, length, far, out):
    """Write into ``out`` the far (``far`` true) or near point of a ray at a distance.

    The ray is ``joint``'s in frame ``t``, the distance ``length`` (clip units) from
    ``(ox, oy, oz)``; ``out`` is ``(3,)``.

    The arithmetic of :func:`handdb.lifting.pinhole.ray_roots`, operation for operation,
    so that the points are bit for bit the same; NaN propagates as there.
    """
    rx, ry, rz = rays[t, joint, 0], rays[t, joint, 1], rays[t, joint, 2]
    a = rx * rx + ry * ry + rz * rz
    b = rx * ox + ry * oy + rz * oz
    nearest = b / a
    miss_sq = ox * ox + oy * oy + oz * oz - b * nearest
    if miss_sq < 0.0:
        miss_sq = 0.0
    reach = length * length - miss_sq
    if reach < 0.0:
        reach = 0.0
    half_chord = math.sqrt(reach / a)
    depth = nearest + half_chord if far else nearest - half_chord
    out[0], out[1], out[2] = rx * depth, ry * depth, rz * depth


@kernel
def _chain_candidates(rays, palm_xyz, chains, chain_bases, lengths, first, second, third,
                      first_bone, second_bone, third_bone):
    """Fill the chain joints and the bone vectors ending at them.

    ``first``, ``second``, ``third`` are :attr:`FingerCandidates.joints`, the bones the
    same shapes; each sign axis's index 0 is the far root, 1 the near one. Clip units.
    """
    for t in range(rays.shape[0]):
        for p in range(2):
            for f in range(chains.shape[0]):
                base = palm_xyz[t, p, chain_bases[f]]
                for a in range(2):
                    one = first[t, p, f, a]
                    _ray_root(rays, t, chains[f, 0], base[0], base[1], base[2],
                              lengths[f, 0], a == 0, one)
                    for k in range(3):
                        first_bone[t, p, f, a, k] = one[k] - base[k]
                    for b in range(2):
                        two = second[t, p, f, a, b]
                        _ray_root(rays, t, chains[f, 1], one[0], one[1], one[2],
                                  lengths[f, 1], b == 0, two)
                        for k in range(3):
                            second_bone[t, p, f, a, b, k] = two[k] - one[k]
                        for c in range(2):
                            three = third[t, p, f, a, b, c]
                            _ray_root(rays, t, chains[f, 2], two[0], two[1], two[2],
                                      lengths[f, 2], c == 0, three)
                            for k in range(3):
                                third_bone[t, p, f, a, b, c, k] = three[k] - two[k]
