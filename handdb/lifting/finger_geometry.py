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

from dataclasses import dataclass

import numpy as np

from handdb.compiled import kernel
from handdb.hand.layout import HandLayout
from handdb.lifting.pinhole import ray_solutions


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
def _chain_candidates(rays, palm_xyz, chains, chain_bases, lengths, first, second, third,
                      first_bone, second_bone, third_bone):
    """Fill the chain joints and the bone vectors ending at them.

    ``first``, ``second``, ``third`` are :attr:`FingerCandidates.joints`, the bones the
    same shapes; each sign axis's index 0 is the far root, 1 the near one. Clip units.
    """
    for t in range(rays.shape[0]):
        for p in range(2):
            for f in range(chains.shape[0]):
                _place(rays, t, chains[f, 0], palm_xyz[t, p, chain_bases[f]], lengths[f, 0],
                       first[t, p, f], first_bone[t, p, f])
                for a in range(2):
                    _place(rays, t, chains[f, 1], first[t, p, f, a], lengths[f, 1],
                           second[t, p, f, a], second_bone[t, p, f, a])
                    for b in range(2):
                        _place(rays, t, chains[f, 2], second[t, p, f, a, b], lengths[f, 2],
                               third[t, p, f, a, b], third_bone[t, p, f, a, b])


@kernel
def _place(rays, t, joint, origin, length, points, bones):
    """Both points of ``joint``'s ray at ``length`` from ``origin`` ``(3,)``, far first.

    Into ``points`` ``(2, 3)``, and the vectors from ``origin`` to them into ``bones``.
    """
    far, near, _ = ray_solutions(rays, t, joint, origin[0], origin[1], origin[2], length)
    for sign, depth in enumerate((far, near)):
        for k in range(3):
            points[sign, k] = rays[t, joint, k] * depth
            bones[sign, k] = points[sign, k] - origin[k]
