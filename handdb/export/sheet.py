"""What a clip's contact sheet shows, shared by the full preview and the thumbnail.

Each column is one frame, evenly spaced over the clip; the top row is the camera's view
(``x`` right, ``y`` down) and the bottom row a side view (depth ``z`` to the right, ``y``
down). Every panel shows one cube of the clip's space, so motion between frames reads at
a glance. Pure numpy: neither drawer's library is imported here.
"""

from __future__ import annotations

import numpy as np

#: Frames shown by default.
DEFAULT_PREVIEW_FRAMES = 6

#: Colour of each finger's bones (and of the palm's), as matplotlib names.
FINGER_COLOURS: dict[str, str] = {
    "thumb": "tab:red", "index": "tab:orange", "middle": "tab:green",
    "ring": "tab:blue", "little": "tab:purple", "palm": "0.35",
}

#: The same colours as 8-bit RGB (matplotlib's tab10 values; ``0.35`` grey).
FINGER_RGB: dict[str, tuple[int, int, int]] = {
    "thumb": (0xD6, 0x27, 0x28), "index": (0xFF, 0x7F, 0x0E), "middle": (0x2C, 0xA0, 0x2C),
    "ring": (0x1F, 0x77, 0xB4), "little": (0x94, 0x67, 0xBD), "palm": (89, 89, 89),
}

#: Joints that were missing and gap-filled: drawn in this colour, a size larger, so the
#: eye finds them (no finger uses magenta).
FILLED_COLOUR = "#ff00ff"
FILLED_RGB: tuple[int, int, int] = (0xFF, 0x00, 0xFF)
#: The ground truth's bones, drawn faintly under the clip's own.
TRUTH_COLOUR = "0.8"
TRUTH_RGB: tuple[int, int, int] = (204, 204, 204)

#: Half the side of a panel, as a fraction of the largest extent of the clip's joints.
HALF_SPAN = 0.55

#: The rows of a sheet: axis label, index of the coordinate across the panel, row name.
VIEWS = (("x", 0, "camera view"), ("z", 2, "side view"))


def preview_frames(n_frames: int, count: int = DEFAULT_PREVIEW_FRAMES) -> np.ndarray:
    """Return ``count`` frame indices evenly spaced from first to last, ``(k,) int``."""
    return np.unique(np.linspace(0, n_frames - 1, min(count, n_frames)).round().astype(int))


def view_box(xyz: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` and half side of the cube every panel shows, clip units (NaN skipped).

    ``xyz`` is ``(T, J, 3)``; a clip without any finite joint gets a unit cube at the origin.
    """
    coordinates = np.ascontiguousarray(xyz.reshape(-1, 3).T)  # (3, T * J), fast to reduce
    low, high = np.fmin.reduce(coordinates, axis=1), np.fmax.reduce(coordinates, axis=1)
    if not np.isfinite(low).all():
        return np.zeros(3), HALF_SPAN
    return (low + high) / 2, HALF_SPAN * max(float((high - low).max()), 1e-9)


def aligned_truth(truth: np.ndarray, xyz: np.ndarray, root: int) -> np.ndarray:
    """Move each frame of ``truth`` so its root lies on the root of ``xyz``, ``(T, J, 3)``.

    Lifting recovers a hand up to its root's position (orthographic clips put the root at
    depth 0), so the truth is compared root to root, as ``validation_joint`` does. Frames
    where either root is NaN stay NaN.
    """
    return truth - truth[:, root:root + 1] + xyz[:, root:root + 1]
