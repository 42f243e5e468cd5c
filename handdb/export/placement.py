"""Where an exported hand stands: in the camera's coordinates, or on the floor at the origin.

Lifted joints are in handdb's camera frame (x right, y down, z away, origin at the camera),
so a hand exported as is stands a camera-distance from the origin and, seen Y up, mostly
below the floor. :func:`at_origin` moves a clip, by one translation for every frame, so that
in the exports' Y-up frame (:data:`handdb.export.rotations.CAMERA_TO_Y_UP`, ``(x, y, z) ->
(x, -y, -z)``):

- the root joint (the wrist) at the first frame that places it is at ``x = z = 0``;
- the lowest point of the clip, over every joint of every frame, is at ``y = 0`` (the
  joints, which every format holds; a skinned mesh reaches a palm's half thickness lower).

The motion itself (every relative position, every rotation) is unchanged.
"""

from __future__ import annotations

import numpy as np

from handdb.hand.skeletons import Skeleton


def origin_shift(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """The translation :func:`at_origin` adds to every joint of every frame.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions, clip units, handdb's camera frame; NaN where
        a joint has no position.
    skeleton
        Skeleton of ``xyz``.

    Returns
    -------
    numpy.ndarray
        ``(3,) float64``, clip units, camera frame; zero when no frame places the root.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    roots = xyz[:, skeleton.root]
    placed = np.flatnonzero(np.isfinite(roots).all(axis=1))
    if len(placed) == 0:
        return np.zeros(3)
    first = roots[placed[0]]
    # Camera y points down, so the lowest point seen Y up is the largest camera y.
    lowest = np.nanmax(xyz[..., 1])
    return np.array([-first[0], -lowest, -first[2]])


def at_origin(xyz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Move a clip so its first placed root is above the origin and its lowest point on the floor.

    Parameters
    ----------
    xyz
        ``(T, J, 3) float64`` joint positions, clip units, handdb's camera frame; NaN where
        a joint has no position (they stay NaN).
    skeleton
        Skeleton of ``xyz``.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 3) float64``, still in the camera frame's axes, translated by
        :func:`origin_shift`: turned Y up, the first placed root has ``x = z = 0`` and the
        minimum ``y`` over the clip is 0. A clip whose root is never placed is unchanged.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    return xyz + origin_shift(xyz, skeleton)
