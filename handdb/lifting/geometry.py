"""Per-bone depth under scaled orthographic projection (thesis §3.5, eqs. 4–6).

A bone of length ``l`` whose ends project ``p`` pixels apart at scale ``s`` (pixels per
clip unit) spans a depth of ``|dZ| = sqrt(l² − (p / s)²)``. The sign of ``dZ`` is the
reflective ambiguity (§3.6) and is left to the lifting methods. All functions are
vectorised over frames (the walks over the skeleton compiled,
:mod:`handdb.compiled`) and never modify their inputs.
"""

from __future__ import annotations

import math

import numpy as np

from handdb.clip import Camera
from handdb.compiled import kernel
from handdb.hand.skeletons import Skeleton


def projected_lengths(uv: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Image length of the bone ending at each joint, ``(T, J) float64`` pixels (root: 0).

    ``uv`` is ``(T, J, 2) float64``, pixels.
    """
    lengths = np.empty(uv.shape[:2])
    _projected_lengths(uv, skeleton.parents, lengths)
    return lengths


@kernel
def _projected_lengths(uv, parents, lengths):
    """Fill ``lengths`` ``(T, J)`` with the image length of each joint's bone (root: 0)."""
    n_frames, n_joints = lengths.shape
    for t in range(n_frames):
        for joint in range(n_joints):
            parent = parents[joint] if parents[joint] >= 0 else joint
            lengths[t, joint] = math.hypot(uv[t, joint, 0] - uv[t, parent, 0],
                                           uv[t, joint, 1] - uv[t, parent, 1])


def eq6_scale(projected: np.ndarray, bone_lengths: np.ndarray, rank: int = 1) -> np.ndarray:
    """Return the thesis's scale (eq. 6): the smallest ``s`` giving every bone a real depth.

    ``s >= p / l`` for every bone, so the smallest admissible scale of a frame is the
    largest ratio of projected length to bone length. (The thesis's appendix program takes
    the minimum ratio and then fixes ``s = 1``; handdb implements the equation.)

    Parameters
    ----------
    projected
        ``(T, J) float64`` image bone lengths, pixels.
    bone_lengths
        ``(J,) float64`` bone lengths, clip units; NaN at the root.
    rank
        1 gives eq. 6; ``k`` gives the ``k``-th largest ratio, the smallest scale at which
        all but ``k − 1`` bones have a real depth (robust to ``k − 1`` outlier bones).

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``, pixels per clip unit; NaN for frames with fewer than ``rank``
        finite ratios.
    """
    scale = np.empty(len(projected))
    _ranked_ratios(projected, bone_lengths, rank, scale)
    return scale


@kernel
def _ranked_ratios(projected, bone_lengths, rank, scale):
    """Fill ``scale`` ``(T,)`` with each frame's ``rank``-th largest finite ratio.

    The ratios are of ``projected`` ``(T, J)`` to ``bone_lengths`` ``(J,)``; NaN where a
    frame has fewer than ``rank``.
    """
    n_frames, n_joints = projected.shape
    top = np.empty(rank)                                    # the largest so far, descending
    for t in range(n_frames):
        found = 0
        for joint in range(n_joints):
            ratio = projected[t, joint] / bone_lengths[joint]
            if not math.isfinite(ratio):
                continue
            found += 1
            if found > rank and ratio <= top[rank - 1]:
                continue
            slot = min(found, rank) - 1
            while slot > 0 and top[slot - 1] < ratio:
                top[slot] = top[slot - 1]
                slot -= 1
            top[slot] = ratio
        scale[t] = top[rank - 1] if found >= rank else np.nan


def depth_magnitudes(
    projected: np.ndarray, bone_lengths: np.ndarray, scale: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Unsigned depth span of every bone (eq. 5), with the discriminant clamped at zero.

    Parameters
    ----------
    projected
        ``(T, J) float64`` image bone lengths, pixels.
    bone_lengths
        ``(J,) float64``, clip units; NaN at the root.
    scale
        ``(T,) float64``, pixels per clip unit.

    Returns
    -------
    abs_dz
        ``(T, J) float64`` clip units, ``|dZ|`` of the bone ending at each joint; NaN at
        the root. Where the track is longer than the bone (``p / s > l``) it is 0.
    inconsistency
        ``(T, J) float64`` clip units, ``max(0, p / s − l)``: how much longer than its
        length the track makes the bone. (The thesis instead lengthens the bone in steps of
        0.001 until the root is real.)
    """
    abs_dz, inconsistency = np.empty(projected.shape), np.empty(projected.shape)
    _depth_magnitudes(projected, bone_lengths, scale, abs_dz, inconsistency)
    return abs_dz, inconsistency


@kernel
def _depth_magnitudes(projected, bone_lengths, scale, abs_dz, inconsistency):
    """Fill :func:`depth_magnitudes`' ``abs_dz`` and ``inconsistency`` ``(T, J)``."""
    n_frames, n_joints = projected.shape
    for t in range(n_frames):
        for joint in range(n_joints):
            in_plane = projected[t, joint] / scale[t]
            length = bone_lengths[joint]
            abs_dz[t, joint] = math.sqrt(_at_least_zero(length * length - in_plane * in_plane))
            inconsistency[t, joint] = _at_least_zero(in_plane - length)


@kernel
def _at_least_zero(x: float) -> float:
    """``max(x, 0)``; NaN stays NaN."""
    return x if math.isnan(x) else max(x, 0.0)


def path_matrix(skeleton: Skeleton) -> np.ndarray:
    """Which bones lie between the root and each joint.

    Returns
    -------
    numpy.ndarray
        ``(J, J) float64``: entry ``[j, k]`` is 1 when the bone ending at joint ``k`` is on
        the path from the root to joint ``j`` (``k = j`` included, the root excluded).
    """
    paths = np.zeros((skeleton.n_joints, skeleton.n_joints))
    for joint in range(skeleton.n_joints):
        parent = skeleton.parents[joint]
        if parent >= 0:
            paths[joint] = paths[parent]
            paths[joint, joint] = 1.0
    return paths


def path_lists(on_path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each row of a boolean matrix is true, as lists a compiled loop can walk.

    Parameters
    ----------
    on_path
        ``(N, M) bool``, e.g. which bones lie on each joint's path (:func:`path_matrix`).

    Returns
    -------
    indices
        ``(N, M) int64``: row ``i``'s true columns in increasing order, then padding.
    counts
        ``(N,) int64``: how many columns of each row are true.
    """
    return (np.argsort(~on_path, axis=1, kind="stable").astype(np.int64),
            np.count_nonzero(on_path, axis=1).astype(np.int64))


def accumulate_depths(signed_dz: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Walk from the root to the tips, adding each bone's signed depth to its parent's.

    Parameters
    ----------
    signed_dz
        ``(..., J) float64``, depth of each joint relative to its parent; ignored at the
        root.
    skeleton
        Gives the tree.

    Returns
    -------
    numpy.ndarray
        ``(..., J) float64`` depth of every joint relative to the root (root: 0); NaN
        below a bone whose depth is NaN. Each joint's depth is the sum of the bones on its
        path taken in joint order (the order of the matrix product by :func:`path_matrix`).
    """
    paths, lengths = path_lists(path_matrix(skeleton) > 0)
    flat = np.reshape(signed_dz, (-1, skeleton.n_joints))
    z = np.empty(flat.shape)
    _sum_paths(flat, paths, lengths, z)
    return z.reshape(np.shape(signed_dz))


@kernel
def _sum_paths(signed_dz, paths, lengths, z):
    """Fill ``z`` ``(N, J)`` with each joint's sum of ``signed_dz`` ``(N, J)`` over its path.

    Joint ``j``'s path is ``paths[j, :lengths[j]]`` (``paths`` ``(J, J)``, ``lengths``
    ``(J,)``); a NaN on the path gives NaN.
    """
    n_rows, n_joints = z.shape
    for row in range(n_rows):
        for joint in range(n_joints):
            total = 0.0
            for step in range(lengths[joint]):
                total += signed_dz[row, paths[joint, step]]
            z[row, joint] = total


def orthographic_points(uv: np.ndarray, scale: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Camera-frame points ``x = u / s, y = v / s`` with the given depth.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    scale
        ``(T,) float64``, pixels per clip unit.
    z
        ``(T, J) float64``, clip units, relative to the root.

    Returns
    -------
    numpy.ndarray
        ``(T, J, 3) float64``, clip units.
    """
    xyz = np.empty(z.shape + (3,))
    _orthographic_points(uv, scale, z, xyz)
    return xyz


@kernel
def _orthographic_points(uv, scale, z, xyz):
    """Fill ``xyz`` ``(T, J, 3)`` with ``(u / s, v / s, z)``."""
    n_frames, n_joints = z.shape
    for t in range(n_frames):
        for joint in range(n_joints):
            xyz[t, joint, 0] = uv[t, joint, 0] / scale[t]
            xyz[t, joint, 1] = uv[t, joint, 1] / scale[t]
            xyz[t, joint, 2] = z[t, joint]


def intrinsics(camera: Camera) -> tuple[float, float, float, float]:
    """``(fx, fy, cx, cy)`` of a pinhole camera, pixels.

    Raises
    ------
    ValueError
        If the camera lacks one of them.
    """
    if camera.fx is None or camera.fy is None or camera.cx is None or camera.cy is None:
        raise ValueError(f"a pinhole camera needs fx, fy, cx and cy (pixels), got {camera}")
    return camera.fx, camera.fy, camera.cx, camera.cy


def centred_pixels(uv: np.ndarray, camera: Camera) -> np.ndarray:
    """Image points a scaled orthographic model can use, ``(T, J, 2) float64`` pixels.

    Orthographic tracks are returned unchanged. Pinhole tracks are taken about the
    principal point and brought to one focal length (the mean of ``fx`` and ``fy``), the
    weak-perspective view of the same camera.
    """
    if camera.model != "pinhole":
        return uv
    fx, fy, cx, cy = intrinsics(camera)
    return (uv - np.array([cx, cy])) * (0.5 * (fx + fy) / np.array([fx, fy]))
