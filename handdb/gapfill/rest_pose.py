"""A flat, open right hand seen from the palm side: the pose a never-seen joint starts from.

Coordinates are in image axes (x right, y down), in units of the wrist-to-middle-MCP
distance, with the wrist at the origin and the fingers pointing up the image. Only the
shape matters: it is always mapped onto a clip's observed joints by an affine fit (which
also mirrors it for a left hand when enough joints are seen).
"""

from __future__ import annotations

import numpy as np

from handdb.errors import SkeletonError
from handdb.hand.skeletons import Skeleton

#: Canonical joint name -> (x, y) of the open right hand, palm towards the camera.
REST_POSE_2D: dict[str, tuple[float, float]] = {
    "wrist": (0.0, 0.0),
    "palm_fold": (0.0, -0.45),
    "palm": (0.0, -0.5),
    "thumb_cmc": (-0.25, -0.15),
    "thumb_mcp": (-0.45, -0.4),
    "thumb_ip": (-0.6, -0.6),
    "thumb_tip": (-0.72, -0.78),
    "index_mcp": (-0.3, -0.95),
    "index_pip": (-0.35, -1.35),
    "index_dip": (-0.37, -1.6),
    "index_tip": (-0.39, -1.8),
    "middle_mcp": (0.0, -1.0),
    "middle_pip": (0.0, -1.45),
    "middle_dip": (0.0, -1.72),
    "middle_tip": (0.0, -1.95),
    "ring_mcp": (0.22, -0.95),
    "ring_pip": (0.26, -1.35),
    "ring_dip": (0.28, -1.6),
    "ring_tip": (0.3, -1.8),
    "little_mcp": (0.42, -0.85),
    "little_pip": (0.5, -1.15),
    "little_dip": (0.54, -1.33),
    "little_tip": (0.57, -1.5),
}


def rest_pose_2d(skeleton: Skeleton) -> np.ndarray:
    """Return the rest pose of ``skeleton``'s joints, ``(J, 2) float64`` in wrist-to-MCP units.

    Raises
    ------
    SkeletonError
        If a joint has no canonical rest position.
    """
    unknown = [j for j in skeleton.joints if j not in REST_POSE_2D]
    if unknown:
        raise SkeletonError(
            f"skeleton '{skeleton.name}': no rest position for joints {unknown}; "
            f"known: {', '.join(REST_POSE_2D)}"
        )
    return np.array([REST_POSE_2D[j] for j in skeleton.joints], dtype=np.float64)
