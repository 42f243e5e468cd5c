"""Masks that hide known points, to score gap filling against the truth.

A mask is a ``(T, J) bool`` array, true where a point is hidden.

* :func:`thesis_table_4_2_mask`: the thesis's Table 4.2, the missing frames of each feature
  point of its 100-frame clenching clip, mapped by joint name through the ``thesis21`` ids
  onto any skeleton (joints the thesis lacks are never hidden).
* :func:`random_gaps_mask`: random interior gaps of 1 to 60 frames, seeded.
* :func:`~handdb.gapfill.occlusion.occlusion_mask`: points hidden from the camera by the
  hand itself (in :mod:`handdb.gapfill.occlusion`).
"""

from __future__ import annotations

import numpy as np

from handdb.errors import ClipDataError
from handdb.hand.skeletons import Skeleton, load_skeleton

#: Frames of the thesis's clip, and of each clip Table 4.2 applies to.
THESIS_CLIP_FRAMES = 100

#: Table 4.2: thesis feature point id -> missing frames (0-based, inclusive ranges).
THESIS_TABLE_4_2: dict[int, tuple[int, int]] = {
    1: (37, 47), 3: (64, 99), 4: (37, 47), 6: (86, 99), 7: (92, 99), 8: (31, 37),
    9: (37, 47), 10: (52, 99), 11: (98, 99), 12: (24, 37), 13: (37, 47), 14: (52, 99),
    16: (33, 37), 17: (37, 47), 18: (50, 99),
}

#: Random gaps: how many, and their length range (frames, inclusive).
RANDOM_GAPS = 40
RANDOM_GAP_FRAMES = (1, 60)


def thesis_table_4_2_mask(skeleton: Skeleton) -> np.ndarray:
    """Table 4.2's missing frames on a 100-frame clip of ``skeleton``.

    Returns
    -------
    numpy.ndarray
        ``(100, J) bool``, true where the thesis hid the point.
    """
    thesis = load_skeleton("thesis21")
    mask = np.zeros((THESIS_CLIP_FRAMES, skeleton.n_joints), dtype=bool)
    for point, (first, last) in THESIS_TABLE_4_2.items():
        name = thesis.joints[thesis.ids.index(point)]
        if name in skeleton.joints:
            mask[first:last + 1, skeleton.index(name)] = True
    return mask


def random_gaps_mask(
    n_frames: int,
    n_joints: int,
    *,
    n_gaps: int = RANDOM_GAPS,
    gap_frames: tuple[int, int] = RANDOM_GAP_FRAMES,
    seed: int = 0,
) -> np.ndarray:
    """Random interior gaps: each hides one joint for a random run of frames.

    Gaps never touch the first or the last frame, so every gap can be bridged. Gaps of the
    same joint may overlap and merge.

    Parameters
    ----------
    n_frames, n_joints
        Shape of the clip.
    n_gaps
        Number of gaps.
    gap_frames
        Shortest and longest gap, frames (inclusive).
    seed
        Seed of the random generator.

    Returns
    -------
    numpy.ndarray
        ``(n_frames, n_joints) bool``.
    """
    shortest, longest = gap_frames
    longest = min(longest, n_frames - 2)
    if longest < shortest:
        raise ClipDataError(f"a {n_frames}-frame clip has no room for {shortest}-frame "
                            "interior gaps")
    rng = np.random.default_rng(seed)
    length = rng.integers(shortest, longest + 1, size=n_gaps)
    start = 1 + (rng.random(n_gaps) * (n_frames - 1 - length)).astype(np.int64)
    joint = rng.integers(0, n_joints, size=n_gaps)
    frames = np.arange(n_frames)
    inside = (frames[None, :] >= start[:, None]) & (frames[None, :] < (start + length)[:, None])
    mask = np.zeros((n_frames, n_joints), dtype=bool)
    np.logical_or.at(mask.T, joint, inside)
    return mask
