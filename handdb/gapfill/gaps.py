"""Gaps in 2D tracks: runs of consecutive missing frames of one joint.

A gap is *interior* when the joint is observed both before and after it, *leading* when it
starts at the first frame, *trailing* when it runs to the last frame, and *whole-clip* when
the joint is never observed. Interpolation can only bridge interior gaps; the other kinds
need the other joints of the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Gaps:
    """Every gap of a clip, one entry per gap, ordered by joint then start frame.

    Attributes
    ----------
    joint
        Joint index of each gap, ``(G,) int64``.
    start
        First missing frame, ``(G,) int64``.
    stop
        One past the last missing frame, ``(G,) int64``.
    n_frames
        Number of frames ``T`` of the clip.
    """

    joint: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    n_frames: int

    def __len__(self) -> int:
        return int(self.joint.size)

    @property
    def length(self) -> np.ndarray:
        """Number of missing frames of each gap, ``(G,) int64``."""
        return self.stop - self.start

    @property
    def leading(self) -> np.ndarray:
        """``(G,) bool``: the gap starts at the first frame."""
        return self.start == 0

    @property
    def trailing(self) -> np.ndarray:
        """``(G,) bool``: the gap runs to the last frame."""
        return self.stop == self.n_frames

    @property
    def whole_clip(self) -> np.ndarray:
        """``(G,) bool``: the joint is missing in every frame."""
        return self.leading & self.trailing

    @property
    def interior(self) -> np.ndarray:
        """``(G,) bool``: the joint is observed just before and just after the gap."""
        return ~self.leading & ~self.trailing

    def select(self, keep: np.ndarray) -> Gaps:
        """Return the gaps where ``keep`` ``(G,) bool`` is true."""
        return Gaps(self.joint[keep], self.start[keep], self.stop[keep], self.n_frames)

    def frames(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every missing point of every gap, flattened.

        Returns
        -------
        gap, frame, joint
            ``(N,) int64`` each: the gap a point belongs to, its frame and its joint.
        """
        lengths = self.length
        gap = np.repeat(np.arange(len(self)), lengths)
        offset = np.arange(gap.size) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        return gap, self.start[gap] + offset, self.joint[gap]


def find_gaps(missing: np.ndarray) -> Gaps:
    """Find the runs of consecutive missing frames of every joint.

    Parameters
    ----------
    missing
        ``(T, J) bool``: the point of joint ``j`` in frame ``t`` is missing.

    Returns
    -------
    Gaps
        The gaps, ordered by joint, then by start frame.
    """
    missing = np.asarray(missing, dtype=bool)
    n_frames, n_joints = missing.shape
    by_joint = np.zeros((n_joints, n_frames + 2), dtype=bool)
    by_joint[:, 1:-1] = missing.T
    # Each joint's row starts and ends unmissing, so its changes alternate start, stop.
    joint, frame = np.divmod(np.flatnonzero(by_joint[:, 1:] != by_joint[:, :-1]), n_frames + 1)
    return Gaps(joint[::2], frame[::2], frame[1::2], int(n_frames))


def mask_points(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns where a 2-D ``mask`` is set, in row-major order.

    The same as ``np.nonzero(mask)``, from one flat scan (several times faster on
    ``(T, J)`` masks).
    """
    return np.divmod(np.flatnonzero(mask), mask.shape[1])
