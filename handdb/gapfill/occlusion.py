"""Occlusion masks: the points the hand itself hides from the camera.

The hand's 3D joints pose the skinned capsule mesh of :mod:`handdb.export.mesh`; from each joint a
ray is cast toward the camera (orthographic: along ``-z`` of the camera frame, toward the
viewer) with trimesh. The joint is hidden when the ray meets the surface of a part of the
hand other than its own: the bones that end or start at it (and the palm, for the palm's
joints).
"""

from __future__ import annotations

import numpy as np

from handdb.export.mesh import hand_mesh, posed_vertices
from handdb.hand.skeletons import Skeleton

#: Direction from a joint toward an orthographic camera, camera frame.
TOWARD_CAMERA = np.array([0.0, 0.0, -1.0])


def _own_parts(skeleton: Skeleton) -> np.ndarray:
    """``(J, J) bool``: mesh part (by its face joint) ``p`` belongs to joint ``j``."""
    own = np.eye(skeleton.n_joints, dtype=bool)
    child = np.flatnonzero(skeleton.parents >= 0)
    own[skeleton.parents[child], child] = True
    palm = np.append(skeleton.root, skeleton.children(skeleton.root))
    own[palm, skeleton.root] = True
    return own


def median_bone_lengths(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Median length of the bone ending at each joint, ``(J,) float64`` (root: 0)."""
    lengths = np.zeros(skeleton.n_joints)
    parent, child = skeleton.bones.T
    lengths[child] = np.nanmedian(np.linalg.norm(xyz[:, child] - xyz[:, parent], axis=-1), axis=0)
    return lengths


def occlusion_mask(
    xyz: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray | None = None
) -> np.ndarray:
    """Points hidden from an orthographic camera by the hand's own mesh.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64``, camera frame (x right, y down, z away from the camera),
        clip units, no NaN.
    skeleton
        The clip's skeleton.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units; the median
        over the clip when ``None``.

    Returns
    -------
    numpy.ndarray
        ``(T, J) bool``: true where the joint is hidden.
    """
    lengths = median_bone_lengths(xyz, skeleton) if bone_lengths is None else bone_lengths
    mesh = hand_mesh(skeleton, lengths)
    vertices = posed_vertices(mesh, xyz, skeleton, lengths)
    own = _own_parts(skeleton)
    directions = np.broadcast_to(TOWARD_CAMERA, (skeleton.n_joints, 3))
    hidden = np.zeros(xyz.shape[:2], dtype=bool)
    for t in range(xyz.shape[0]):
        posed = mesh.to_trimesh(vertices[t])
        faces, rays = posed.ray.intersects_id(xyz[t], directions, multiple_hits=True)
        foreign = ~own[rays, mesh.face_joints[faces]]
        hidden[t, rays[foreign]] = True
    return hidden
