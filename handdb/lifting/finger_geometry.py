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

from handdb.hand.layout import HandLayout
from handdb.lifting.pinhole import ray_roots


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
    chain_rays = rays[:, None, layout.chains]                            # (T, 1, F, 3, 3)
    lengths = bone_lengths[layout.chains]                                # (F, 3)
    base = palm_xyz[:, :, layout.chain_bases]                            # (T, 2, F, 3)

    def both(origin: np.ndarray, ray: np.ndarray, length: np.ndarray) -> np.ndarray:
        far, near, _ = ray_roots(origin, ray, length)
        return np.stack([far, near], axis=-2)

    first = both(base, chain_rays[:, :, :, 0], lengths[:, 0])            # (T, 2, F, 2, 3)
    second = both(first, chain_rays[:, :, :, None, 1], lengths[:, 1, None])
    third = both(second, chain_rays[:, :, :, None, None, 2], lengths[:, 2, None, None])
    bones = ((first - base[..., None, :])[..., :, None, None, :],
             (second - first[..., None, :])[..., None, :],
             third - second[..., None, :])
    return FingerCandidates(anchors=palm_xyz[:, :, anchor_joints(layout)], bones=bones,
                            joints=(first, second, third), palm=palm_xyz)
