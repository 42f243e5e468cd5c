"""Perspective lifting: joints on their camera rays, depth from the bone lengths.

Through a pinhole camera a joint lies on the ray ``Z · r`` with
``r = ((u − cx) / fx, (v − cy) / fy, 1)``. Given its parent's position ``P`` and the bone
length ``l``, ``|Z r − P| = l`` is a quadratic in ``Z`` whose two roots are the far and near
solutions (the reflective ambiguity, now asymmetric; :func:`ray_roots`). A negative
discriminant (the ray passes farther than ``l`` from ``P``) is clamped: the joint goes to
the ray's point nearest ``P`` and the excess distance is recorded. Which root each bone
takes is the hand prior's decision (:mod:`handdb.lifting.kinematic`).

The root's depth is the largest at which some choice of solutions keeps (nearly) every
bone real, the perspective form of eq. 6 (:func:`deepest_feasible_root`), then lightly
smoothed over time (:func:`estimate_root_depth`).
"""

from __future__ import annotations

import math

import numpy as np

from handdb.clip import Camera, finite_points
from handdb.compiled import kernel
from handdb.hand.skeletons import Skeleton
from handdb.lifting.geometry import intrinsics
from handdb.lifting.temporal import smooth_scale
from handdb.vectors import dot

#: The root depth is searched within these factors of the weak-perspective guess.
DEPTH_BRACKET = (0.5, 3.0)

#: Candidate root depths tried per frame, on a geometric grid across the bracket.
DEPTH_GRID = 48

#: Bisection steps refining the deepest feasible candidate (each halves a grid step).
BISECTION_STEPS = 12

#: Smoothing of the per-frame root depth bounds (of their inverses, as for the scale): the
#: median over +-2 frames, then a Gaussian of 1 frame. A frame's bound is close to the
#: truth while the hand's distance changes by a few per cent within a second, so a short
#: window follows the motion where a long one lags it.
ROOT_DEPTH_PERCENTILE = 50.0
ROOT_DEPTH_HALF_WINDOW = 2
ROOT_DEPTH_SMOOTHING_FRAMES = 1.0

#: A root depth counts as feasible while the least summed excess of the bones stays below
#: this share of their total length: room for tracking noise (the choice is measured in
#: ``benchmarks/RESULTS-lifting.md``).
EXCESS_TOLERANCE = 1e-4


def camera_rays(uv: np.ndarray, camera: Camera) -> np.ndarray:
    """Ray direction of each image point with unit depth, ``(T, J, 3) float64``."""
    fx, fy, cx, cy = intrinsics(camera)
    x = (uv[..., 0] - cx) / fx
    y = (uv[..., 1] - cy) / fy
    return np.stack([x, y, np.ones_like(x)], axis=-1)


def ray_roots(origin: np.ndarray, ray: np.ndarray,
              length: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Find the two points of a ray at a given distance from a point.

    Parameters
    ----------
    origin
        ``(..., 3) float64``, clip units: the parent joint.
    ray
        ``(..., 3) float64``: the child's ray (unit depth).
    length
        Bone length, clip units (broadcasts against ``origin[..., 0]``).

    Returns
    -------
    far, near
        ``(..., 3) float64``: the points of the ray at distance ``length`` from
        ``origin``, the deeper first; both the ray's point nearest ``origin`` when the ray
        passes farther than ``length`` from it.
    excess
        ``(...) float64`` >= 0, clip units: by how much the ray misses the sphere.
    """
    a = dot(ray, ray)
    b = dot(ray, origin)
    nearest = b / a
    miss_sq = np.clip(dot(origin, origin) - b * nearest, 0.0, None)
    half_chord = np.sqrt(np.clip(length**2 - miss_sq, 0.0, None) / a)
    far = ray * (nearest + half_chord)[..., None]
    near = ray * (nearest - half_chord)[..., None]
    return far, near, np.clip(np.sqrt(miss_sq) - length, 0.0, None)


def walk_rays(rays: np.ndarray, root_depth: np.ndarray, skeleton: Skeleton,
              bone_lengths: np.ndarray, bone_dz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Place every joint on its ray, from the root to the tips.

    Parameters
    ----------
    rays
        ``(T, J, 3) float64`` from :func:`camera_rays`.
    root_depth
        ``(T,) float64``, clip units: depth ``Z`` of the root.
    skeleton
        Gives the tree.
    bone_lengths
        ``(J,) float64``, clip units.
    bone_dz
        ``(T, J) float64``, clip units: each bone's depth relative to its parent as first
        estimated; of the two points :func:`ray_roots` offers, the one whose depth is
        nearer the parent's plus ``bone_dz`` is taken.

    Returns
    -------
    xyz
        ``(T, J, 3) float64``, clip units, camera frame.
    inconsistency
        ``(T, J) float64`` >= 0, clip units: how much farther than its bone length the ray
        passes from the parent (0 at the root).
    """
    xyz = np.empty(rays.shape)
    inconsistency = np.zeros(bone_dz.shape)
    _walk_rays(rays, root_depth, skeleton.root, skeleton.parents, bone_lengths, bone_dz, xyz,
               inconsistency)
    return xyz, inconsistency


@kernel
def ray_solutions(rays, t, joint, x, y, z, length):
    """Depths of the two points of a ray at a distance from a point, and the miss.

    The ray is ``joint``'s in frame ``t`` of ``rays`` ``(T, J, 3)``, the point
    ``(x, y, z)`` and the distance ``length``, clip units. Returns ``(far, near,
    excess)``: the depths of the two points (the ray's nearest point twice when it misses
    the sphere) and by how much it misses (>= 0). The arithmetic of :func:`ray_roots`,
    operation for operation, so bit for bit the same; NaN propagates as there.
    """
    rx, ry, rz = rays[t, joint, 0], rays[t, joint, 1], rays[t, joint, 2]
    a = rx * rx + ry * ry + rz * rz
    b = rx * x + ry * y + rz * z
    nearest = b / a
    miss_sq = x * x + y * y + z * z - b * nearest
    if miss_sq < 0.0:
        miss_sq = 0.0
    reach = length * length - miss_sq
    if reach < 0.0:
        reach = 0.0
    half_chord = math.sqrt(reach / a)
    excess = math.sqrt(miss_sq) - length
    if excess < 0.0:
        excess = 0.0
    return nearest + half_chord, nearest - half_chord, excess


@kernel
def _walk_rays(rays, root_depth, root, parents, bone_lengths, bone_dz, xyz, inconsistency):
    """Fill ``xyz`` ``(T, J, 3)`` and ``inconsistency`` ``(T, J)``; see :func:`walk_rays`.

    Joints are placed in index order, each parent before its children.
    """
    for t in range(rays.shape[0]):
        for k in range(3):
            xyz[t, root, k] = rays[t, root, k] * root_depth[t]
        for joint in range(rays.shape[1]):
            parent = parents[joint]
            if parent < 0:
                continue
            x, y, z = xyz[t, parent, 0], xyz[t, parent, 1], xyz[t, parent, 2]
            far, near, excess = ray_solutions(rays, t, joint, x, y, z, bone_lengths[joint])
            wanted = z + bone_dz[t, joint]
            depth = far if abs(rays[t, joint, 2] * far - wanted) \
                <= abs(rays[t, joint, 2] * near - wanted) else near
            for k in range(3):
                xyz[t, joint, k] = rays[t, joint, k] * depth
            inconsistency[t, joint] = excess


def deepest_feasible_root(rays: np.ndarray, guess: np.ndarray, skeleton: Skeleton,
                          bone_lengths: np.ndarray) -> np.ndarray:
    """Largest root depth per frame at which some pose with these bone lengths fits the rays.

    A root depth is feasible when some choice of near or far solution for every bone
    (:func:`ray_roots`) keeps the bones' summed excess within :data:`EXCESS_TOLERANCE` of
    their total length; the least excess over all choices is found exactly, bone by bone
    from the tips up. Below the true depth the hand has room to spare, above it a bone in
    (or near) the image plane can no longer reach its child's ray: the deepest feasible
    depth is eq. 6 through a pinhole. The feasible depths need not form one interval, so
    candidates on a geometric grid are tried from the deepest down and the first feasible
    one is refined by bisection toward the next, infeasible, candidate.

    Parameters
    ----------
    rays
        ``(T, J, 3) float64`` from :func:`camera_rays`.
    guess
        ``(T,) float64``, clip units: a first guess (weak perspective); the answer is
        searched within :data:`DEPTH_BRACKET` of it.
    skeleton, bone_lengths
        The clip's skeleton and its bone lengths (clip units).

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``, clip units.
    """
    steps = np.linspace(np.log(DEPTH_BRACKET[0]), np.log(DEPTH_BRACKET[1]), DEPTH_GRID)
    order = np.argsort(skeleton.parents, kind="stable")
    children = order[skeleton.parents[order] >= 0]                      # grouped by parent
    first_child = np.searchsorted(skeleton.parents[children], np.arange(skeleton.n_joints + 1))
    depth = np.empty(len(rays))
    _deepest_feasible(rays, skeleton.root, children, first_child, bone_lengths,
                      np.log(guess), steps, EXCESS_TOLERANCE * np.nansum(bone_lengths),
                      depth)
    return depth


@kernel
def _deepest_feasible(rays, root, children, first_child, bone_lengths, log_guess, steps,
                      tolerance, depth):
    """Fill ``depth`` ``(T,)``: each frame's deepest feasible candidate, then bisected.

    The candidates are ``exp(log_guess + steps)``; the bisection runs
    :data:`BISECTION_STEPS` times toward the next, infeasible, candidate. The joints'
    children are ``children[first_child[j]:first_child[j + 1]]``.
    """
    for t in range(len(rays)):
        deepest = 0
        for g in range(len(steps) - 1, -1, -1):
            if _fits(rays, t, root, log_guess[t] + steps[g], children, first_child,
                     bone_lengths, tolerance):
                deepest = g
                break
        low = log_guess[t] + steps[deepest]
        high = low + (steps[1] - steps[0])
        for _ in range(BISECTION_STEPS):
            middle = 0.5 * (low + high)
            if _fits(rays, t, root, middle, children, first_child, bone_lengths, tolerance):
                low = middle
            else:
                high = middle
        depth[t] = math.exp(low)


@kernel
def _fits(rays, t, root, log_depth, children, first_child, bone_lengths, tolerance):
    """Whether frame ``t``'s pose can hang from the root at depth ``exp(log_depth)``."""
    root_depth = math.exp(log_depth)
    return _least_excess(rays, t, root, rays[t, root, 0] * root_depth,
                         rays[t, root, 1] * root_depth, root_depth, children, first_child,
                         bone_lengths, tolerance) <= tolerance


@kernel
def _least_excess(rays, t, joint, x, y, z, children, first_child, bone_lengths, budget):
    """Least summed excess of frame ``t``'s bones below ``joint`` placed at ``(x, y, z)``.

    Each child lies on its ray at its bone's length from ``joint`` (near or far solution,
    whichever leaves less excess below it), or, where the ray passes too far, at the ray's
    nearest point, the miss counting as excess. NaN (a missing point) counts as none. The
    search stops as soon as the excess passes ``budget``, returning a value above it.
    ``rays`` ``(T, J, 3)`` is indexed element by element: a view of a frame or a ray per
    call costs this recursion three times its arithmetic.
    """
    total = 0.0
    for i in range(first_child[joint], first_child[joint + 1]):
        child = children[i]
        rx, ry, rz = rays[t, child, 0], rays[t, child, 1], rays[t, child, 2]
        far, near, excess = ray_solutions(rays, t, child, x, y, z, bone_lengths[child])
        if math.isnan(excess):
            continue
        total += excess
        if total > budget:
            return total
        below = _least_excess(rays, t, child, rx * far, ry * far, rz * far, children,
                              first_child, bone_lengths, budget - total)
        if far > near and below > 0.0:
            below = min(below, _least_excess(rays, t, child, rx * near, ry * near, rz * near,
                                             children, first_child, bone_lengths,
                                             min(budget - total, below)))
        total += below
        if total > budget:
            return total
    return total


def estimate_root_depth(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
               camera: Camera, weak_scale: np.ndarray) -> np.ndarray:
    """Depth of the root per frame: the perspective eq. 6, robust and smooth over time.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels.
    skeleton, bone_lengths
        The clip's skeleton and bone lengths (clip units).
    camera
        A pinhole camera.
    weak_scale
        ``(T,) float64``, pixels per clip unit, of the weak-perspective view: the root's
        depth is first guessed as ``focal / weak_scale``.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``, clip units. A frame with no point observed bounds nothing (any
        depth fits it) and takes its neighbours' depth.
    """
    fx, fy, _, _ = intrinsics(camera)
    focal = 0.5 * (fx + fy)
    rays = camera_rays(uv, camera)
    bound = deepest_feasible_root(rays, focal / weak_scale, skeleton, bone_lengths)
    bound[~finite_points(rays).any(axis=-1)] = np.nan
    return 1.0 / smooth_scale(1.0 / bound, ROOT_DEPTH_PERCENTILE, ROOT_DEPTH_HALF_WINDOW,
                              ROOT_DEPTH_SMOOTHING_FRAMES)
