"""A flat, open right hand seen from the palm side: the pose a never-seen joint starts from.

The average hand of :func:`handdb.hand.shape.mean_shape`, palm to the camera and fingers up
the image, in image axes (x right, y down), in units of the wrist-to-middle-MCP distance,
the wrist at the origin. Only the shape matters: it is always mapped onto a clip's observed
joints by an affine fit (which also mirrors it for a left hand when enough joints are seen).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import Skeleton

#: Image axes of the hand frame's ``x`` and ``y`` seen palm first, fingers up.
_IMAGE_AXES = np.array([[1.0, 0.0], [0.0, -1.0], [0.0, 0.0]])


@cache
def _rest(joints: tuple[str, ...]) -> np.ndarray:
    shape = mean_shape()
    points = np.stack([shape.point(joint) for joint in joints]) - shape.point("wrist")
    unit = np.linalg.norm(shape.point("middle_mcp") - shape.point("wrist"))
    rest = points @ _IMAGE_AXES / unit
    rest.flags.writeable = False
    return rest


def rest_pose_2d(skeleton: Skeleton) -> np.ndarray:
    """Return the rest pose of ``skeleton``'s joints, ``(J, 2) float64`` in wrist-to-MCP units.

    Raises
    ------
    SkeletonError
        If a joint has no place in the hand shape.
    """
    return _rest(skeleton.joints).copy()
