"""Gaps in 2D tracks: runs of consecutive missing frames of one joint.

A gap is *interior* when the joint is observed both before and after it, *leading* when it
starts at the first frame, *trailing* when it runs to the last frame, and *whole-clip* when
the joint is never observed. Interpolation can only bridge interior gaps; the other kinds
need the other joints of the hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.compiled import kernel


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
        return _gap_points(self.joint, self.start, self.stop)


@kernel
def _gap_points(
    joint: np.ndarray, start: np.ndarray, stop: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`Gaps.frames` of the gaps ``joint``, ``start``, ``stop``, ``(G,) int64`` each."""
    n_points = np.sum(stop - start)
    gap = np.empty(n_points, dtype=np.int64)
    frame, joint_of = np.empty_like(gap), np.empty_like(gap)
    point = 0
    for g in range(joint.size):
        for t in range(start[g], stop[g]):
            gap[point], frame[point], joint_of[point] = g, t, joint[g]
            point += 1
    return gap, frame, joint_of


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
    return Gaps(*_runs(missing), int(missing.shape[0]))


@kernel
def _runs(missing: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs of true values down each column of ``missing`` ``(T, J) bool``.

    Returns ``(G,) int64`` joints, starts and stops (exclusive), ordered by joint, then start.
    """
    n_frames, n_joints = missing.shape
    most = n_joints * ((n_frames + 1) // 2)
    joint, start, stop = (np.empty(most, dtype=np.int64), np.empty(most, dtype=np.int64),
                          np.empty(most, dtype=np.int64))
    n_runs = 0
    for j in range(n_joints):
        for t in range(n_frames):
            if missing[t, j] and (t == 0 or not missing[t - 1, j]):
                joint[n_runs], start[n_runs] = j, t
            if missing[t, j] and (t == n_frames - 1 or not missing[t + 1, j]):
                stop[n_runs] = t + 1
                n_runs += 1
    return joint[:n_runs].copy(), start[:n_runs].copy(), stop[:n_runs].copy()


def mask_points(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns where a 2-D ``mask`` is set, in row-major order.

    The same as ``np.nonzero(mask)``, from one flat scan (several times faster on
    ``(T, J)`` masks).
    """
    return np.divmod(np.flatnonzero(mask), mask.shape[1])
