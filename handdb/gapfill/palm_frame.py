"""The palm's image motion, and tracks seen from the palm (the palm frame).

The palm points (:func:`~handdb.gapfill.rigid.palm_joints`) move nearly as one rigid body,
which an orthographic camera shows as a 2D affine map per frame. :func:`palm_motion` finds
that map for every frame: it fits the observed palm points to a reference palm (the median
palm shape of the frames that show the whole palm, found by aligning them to the rest pose,
then to that median), and interpolates the map's six parameters over time in frames with
fewer than three palm points, correcting them by a similarity. A frame showing exactly three
palm points is treated the same way when other frames of the clip show more: an affine map
through three points is exact (six equations, six parameters), so it passes through their
detector noise and carries it, magnified, to every palm point it places (the further from
the three, the more: a knuckle beside a thin wrist-thumb-index triangle moved by 50 px under
3 px of noise on the MediaPipe clips).
Expressed in the palm frame (:func:`to_palm_frame`), palm points stand still and finger
points move only as the fingers bend: gaps there are far easier to bridge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from handdb.gapfill.rest_pose import rest_pose_2d
from handdb.gapfill.rigid import palm_joints, placeable_frames
from handdb.gapfill.transfer import (
    AFFINE,
    NO_MAP,
    apply_affine,
    apply_linear,
    fit_maps,
    fit_maps_from_shape,
    inverse_2x2,
)
from handdb.hand.skeletons import Skeleton

#: Points an affine map fits exactly: six equations for its six parameters, none to spare
#: against noise.
EXACT_AFFINE_POINTS = 3


@dataclass(frozen=True)
class PalmMotion:
    """The affine map from the palm frame to the image in every frame.

    Attributes
    ----------
    linear
        ``(T, 2, 2) float64``.
    offset
        ``(T, 2) float64``, pixels: image = ``linear @ palm_frame + offset``.
    fitted
        ``(T,) bool``: fitted to the frame's own palm points, at least three and not in a
        line, and more than :data:`EXACT_AFFINE_POINTS` if any frame shows that many (else
        interpolated in time and corrected).
    """

    linear: np.ndarray
    offset: np.ndarray
    fitted: np.ndarray


def _interpolate_in_time(values: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Interpolate ``(T, ...)`` values linearly in time where not ``known`` ``(T,) bool``."""
    frames = np.arange(values.shape[0])
    flat = values.reshape(values.shape[0], -1).copy()
    unknown = np.flatnonzero(~known)
    for column in flat.T:
        column[unknown] = np.interp(unknown, frames[known], column[known])
    return flat.reshape(values.shape)


def _median(points: np.ndarray) -> np.ndarray:
    """The median ``(K, 2)`` of ``(N, K, 2)`` points over ``N``, NaN ignored."""
    return np.nanmedian(points, axis=0) if np.isnan(points).any() else np.median(points, axis=0)


def palm_motion(uv: np.ndarray, missing: np.ndarray, skeleton: Skeleton) -> PalmMotion | None:
    """Fit the palm's affine motion, frame by frame.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels, NaN where missing.
    missing
        ``(T, J) bool``.
    skeleton
        The clip's skeleton.

    Returns
    -------
    PalmMotion or None
        ``None`` when no frame shows :data:`~handdb.gapfill.rigid.MIN_PALM_POINTS` palm
        points spread enough for an affine fit.
    """
    if not placeable_frames(missing, skeleton).any():
        return None
    palm = palm_joints(skeleton)
    palm_seen = ~missing & palm
    palm_index = np.flatnonzero(palm)
    points, seen = np.take(uv, palm_index, axis=1), np.take(palm_seen, palm_index, axis=1)
    complete = np.asarray(seen.all(axis=1), dtype=bool)
    # The reference is shaped by the frames showing the whole palm (else by every frame
    # whose fit is affine): only those are fitted while shaping it.
    shape_from = np.flatnonzero(complete) if complete.any() else np.arange(len(uv))
    shape_points, shape_seen = points[shape_from], seen[shape_from]
    reference = rest_pose_2d(skeleton)[palm]
    for _ in range(2):
        linear, offset, kind = fit_maps_from_shape(reference, shape_points, shape_seen)
        fitted = kind == AFFINE
        shaping = complete[shape_from] if complete.any() else fitted
        linear[~fitted] = np.eye(2)
        inverse = inverse_2x2(linear)
        canonical = apply_affine(inverse, -apply_linear(inverse, offset), shape_points)
        canonical[~(shape_seen & shaping[:, None])] = np.nan
        seen_once = ~np.isnan(canonical[..., 0]).all(axis=0)
        canonical[:, ~seen_once] = 0.0
        reference = np.where(seen_once[:, None], _median(canonical), reference)
    linear, offset, kind = fit_maps_from_shape(reference, points, seen)
    fitted = kind == AFFINE
    spare = seen.sum(axis=1) > EXACT_AFFINE_POINTS
    if (fitted & spare).any():
        fitted &= spare
    if not fitted.any():
        return None
    linear = _interpolate_in_time(linear, fitted)
    offset = _interpolate_in_time(offset, fitted)
    interpolated = np.flatnonzero(~fitted)
    predicted = reference @ np.swapaxes(linear[interpolated], 1, 2) + offset[interpolated, None]
    correction, shift, kind = fit_maps(predicted, points[interpolated], seen[interpolated],
                                       affine=False)
    corrected = interpolated[kind > NO_MAP]
    correction, shift = correction[kind > NO_MAP], shift[kind > NO_MAP]
    linear[corrected] = correction @ linear[corrected]
    offset[corrected] = apply_linear(correction, offset[corrected]) + shift
    return PalmMotion(linear=linear, offset=offset, fitted=fitted)


def to_palm_frame(uv: np.ndarray, motion: PalmMotion) -> np.ndarray:
    """Express image points in the palm frame, ``(T, J, 2) -> (T, J, 2)``."""
    inverse = inverse_2x2(motion.linear)
    return apply_affine(inverse, -apply_linear(inverse, motion.offset), uv)


def to_image(points: np.ndarray, motion: PalmMotion, frame: np.ndarray | None = None
             ) -> np.ndarray:
    """Map palm-frame points back to the image, pixels.

    ``points`` are ``(T, J, 2)``, or ``(N, 2)`` seen in frames ``frame`` ``(N,) int64``.
    """
    if frame is None:
        return apply_affine(motion.linear, motion.offset, points)
    return apply_linear(motion.linear[frame], points) + motion.offset[frame]
