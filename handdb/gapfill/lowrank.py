"""Low-rank reconstruction of missing points from the other joints.

After Gløersen & Federolf (2016, PLoS ONE 11(3): e0152616): the trajectories of all joints
form a ``(T, 2J)`` matrix whose columns are strongly correlated, so a few principal
components describe every frame. Each column is centred and scaled to unit variance, the
principal components that explain ``variance`` of the data are found, and each frame's missing
coordinates are reconstructed from the component scores that best fit its observed
coordinates (ridge-regularised least squares, solved once per pattern of missing
coordinates). The filled matrix gives new components; this is iterated until the filled
values stop changing, or for :data:`MAX_ITERATIONS`. The gaps start out linearly
interpolated.

The reconstruction of an observed point is not exactly its observation, so a gap filled
from the model alone would jump at its ends. :func:`blend_to_edges` adds the model's
residual at the frames bounding each gap, interpolated linearly across it (held on the
one known side of a leading or trailing gap), so the fill meets the observations.
"""

from __future__ import annotations

import numpy as np

from handdb.gapfill.gaps import Gaps, find_gaps
from handdb.gapfill.interpolate import interpolate_gaps
from handdb.gapfill.registry import MethodOutput
from handdb.gapfill.rigid import place_from_rest_pose
from handdb.hand.skeletons import Skeleton

#: Share of the variance of the normalised trajectories the components keep.
DEFAULT_VARIANCE = 0.995
#: Iterations at most.
MAX_ITERATIONS = 100
#: Stop when no filled value moves more than this share of its column's spread.
TOLERANCE = 1e-4
#: Ridge weight on the component scores (normalised units), so frames with few observed
#: coordinates stay determined.
RIDGE = 1e-3
#: Columns with a spread below this (pixels) are not scaled up.
MIN_SPREAD = 1e-9


def _component_count(eigenvalues: np.ndarray, variance: float, limit: int) -> int:
    share = np.cumsum(eigenvalues) / max(eigenvalues.sum(), MIN_SPREAD)
    return min(int(np.searchsorted(share, variance)) + 1, limit)


def lowrank_reconstruct(
    uv: np.ndarray,
    missing: np.ndarray,
    *,
    initial: np.ndarray | None = None,
    variance: float = DEFAULT_VARIANCE,
    max_iterations: int = MAX_ITERATIONS,
    tolerance: float = TOLERANCE,
) -> np.ndarray:
    """Reconstruct every point of the joints observed at least once from a low-rank model.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, NaN where missing.
    missing
        ``(T, J) bool``.
    initial
        ``(T, J, 2) float64``: first estimates of the missing points (a good start saves
        iterations); linear interpolation when ``None``.
    variance
        Share of the normalised variance the principal components keep, in (0, 1].
    max_iterations, tolerance
        Iteration limit and convergence threshold (share of each column's spread).

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: the model's value of every point (observed ones too), NaN
        for joints never observed.
    """
    n_frames, n_joints = missing.shape
    seen = ~missing.all(axis=0)
    columns = np.repeat(seen, 2)
    known = np.repeat(~missing[:, seen], 2, axis=1)
    patterns, pattern_of_frame = np.unique(known, axis=0, return_inverse=True)
    start = interpolate_gaps(uv, missing, "linear") if initial is None else initial
    data = np.where(missing[..., None], start, uv)[:, seen].reshape(n_frames, -1)
    for _ in range(max_iterations):
        mean = data.mean(axis=0)
        spread = np.maximum(data.std(axis=0), MIN_SPREAD)
        normal = (data - mean) / spread
        eigenvalues, eigenvectors = np.linalg.eigh(normal.T @ normal)
        k = _component_count(eigenvalues[::-1], variance, normal.shape[1])
        basis = eigenvectors[:, ::-1][:, :k]
        gram = np.swapaxes(patterns[:, :, None] * basis, 1, 2) @ basis + RIDGE * np.eye(k)
        rhs = (normal * known) @ basis
        scores = (np.linalg.inv(gram)[pattern_of_frame.ravel()] @ rhs[..., None])[..., 0]
        model = (scores @ basis.T) * spread + mean
        updated = np.where(known, data, model)
        change = np.max(np.abs(updated - data) / spread, initial=0.0)
        data = updated
        if change < tolerance:
            break
    result = np.full((n_frames, n_joints * 2), np.nan)
    result[:, columns] = model
    return result.reshape(n_frames, n_joints, 2)


def blend_to_edges(uv: np.ndarray, model: np.ndarray, gaps: Gaps) -> np.ndarray:
    """Fill ``gaps`` with ``model`` plus its residual at the gap's ends, blended across.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, observed at the frames bounding each gap.
    model
        ``(T, J, 2) float64``: a model's value of every point.
    gaps
        Gaps that are not whole-clip.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 2) float64``: ``uv`` with the gaps filled.
    """
    gap, frame, joint = gaps.frames()
    before = np.maximum(gaps.start[gap] - 1, 0)
    after = np.minimum(gaps.stop[gap], gaps.n_frames - 1)
    residual_before = uv[before, joint] - model[before, joint]
    residual_after = uv[after, joint] - model[after, joint]
    share_after = ((frame - before) / np.maximum(after - before, 1))[:, None]
    residual = (1 - share_after) * residual_before + share_after * residual_after
    residual = np.where(gaps.leading[gap][:, None], residual_after, residual)
    residual = np.where(gaps.trailing[gap][:, None], residual_before, residual)
    filled = uv.copy()
    filled[frame, joint] = model[frame, joint] + residual
    return filled


def fill_lowrank(
    uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton, *, variance: float = DEFAULT_VARIANCE
) -> MethodOutput:
    """Fill every gap from the low-rank model, blended to the observations at its ends."""
    gaps = find_gaps(missing)
    model = lowrank_reconstruct(uv, missing, variance=variance)
    filled = blend_to_edges(uv, model, gaps.select(~gaps.whole_clip))
    never_seen = np.unique(gaps.joint[gaps.whole_clip])
    if never_seen.size:
        filled = place_from_rest_pose(filled, missing, skeleton, never_seen)
    return MethodOutput(filled)
