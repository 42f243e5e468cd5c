"""Candidate 3D bones of every finger sign state, seen orthographically or through a pinhole.

The hand prior (:mod:`handdb.lifting.hand_prior`) scores each finger's eight sign states
under each of the palm's two tilt states. What it needs is, per palm state, where the palm
is (the wrist, the index and little MCP joints and the joint each finger hangs from) and,
per finger state, the three bone vectors below the palm. Orthographically a bone's vector
depends on its own sign only, ``(dx, dy, ±|dZ|)``; through a pinhole it depends on every
sign above it, since the parent's depth decides where along its ray the child can lie.
Sign axes are ordered like :data:`handdb.lifting.hand_prior.SIGN_STATES`: index 0 is the
positive (deeper) choice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.lifting.hand_layout import HandLayout
from handdb.lifting.pinhole import ray_roots
from handdb.skeletons import Skeleton


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
        where the chain joints lie (pinhole only; ``None`` orthographically).
    palm
        ``(T, 2, J, 3) float64``: every joint of the palm in each palm state (pinhole only).
    """

    anchors: np.ndarray
    bones: tuple[np.ndarray, np.ndarray, np.ndarray]
    joints: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    palm: np.ndarray | None = None


def anchor_joints(layout: HandLayout) -> np.ndarray:
    """Joints of :attr:`FingerCandidates.anchors`, ``(3 + F,) int64``."""
    return np.concatenate([[layout.wrist, layout.index_mcp, layout.little_mcp],
                           layout.chain_bases])


def orthographic_candidates(xy: np.ndarray, abs_dz: np.ndarray, palm_z: np.ndarray,
                            skeleton: Skeleton, layout: HandLayout) -> FingerCandidates:
    """Candidates under scaled orthographic projection.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.
    palm_z
        ``(T, 2, J) float64``: depth of the palm joints relative to the root in palm state
        0 and 1 (other joints: ignored).
    skeleton, layout
        The clip's skeleton, its palm and fingers.
    """
    # Built component by component, each a contiguous fill, and then viewed with the
    # components last: numpy fills an array with a small last axis slowly.
    anchors = anchor_joints(layout)
    chains = layout.chains
    x, y = xy[..., 0], xy[..., 1]
    points = np.empty((3,) + palm_z.shape[:2] + (len(anchors),))        # (3, T, 2, A)
    points[0] = x[:, None, anchors]
    points[1] = y[:, None, anchors]
    points[2] = palm_z[:, :, anchors]
    parents = skeleton.parents[chains]
    vectors = np.empty((3, 2, len(xy), 1) + chains.shape)                # (3, 2, T, 1, F, 3)
    vectors[0] = (x[:, chains] - x[:, parents])[:, None]
    vectors[1] = (y[:, chains] - y[:, parents])[:, None]
    vectors[2, 0] = abs_dz[:, None, chains]
    vectors[2, 1] = -vectors[2, 0]
    points = np.moveaxis(points, 0, -1)
    vectors = vectors.transpose(2, 3, 4, 5, 1, 0)                        # (T, 1, F, 3, 2, 3)
    bones = (vectors[:, :, :, 0][..., :, None, None, :],
             vectors[:, :, :, 1][..., None, :, None, :],
             vectors[:, :, :, 2][..., None, None, :, :])
    return FingerCandidates(anchors=points, bones=bones)


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
