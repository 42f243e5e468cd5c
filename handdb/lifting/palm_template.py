"""The rigid palm: its shape recovered from the clip's own 2D track, and its pose per frame.

The palm without the thumb (the root, a palm centre where the skeleton has one, and the
long fingers' MCP joints) is a near-rigid body, but not a plane: the metacarpals arch,
the wrist point of an annotation lies in front of or behind the knuckles. Seen by a
scaled orthographic camera (:mod:`handdb.lifting.geometry`) from several directions, its
3D shape, the *template* ``S`` (``K`` joints, the root at the origin), follows from the
track alone, up to a mirror image:

1. **Start.** In a sample of frames the per-frame plane fit (:func:`handdb.lifting.palm.
   palm_signs`) gives the joints' depths; the frames' point sets are averaged by
   Procrustes alignment (reflections allowed, the median of the aligned sets), and every
   joint is put at its known bone length from its parent.
2. **Poses** (:func:`fit_tilts`). A near-planar template seen from one frame has two
   poses that explain the image about equally well, tilted either way (the Necker pair).
   Both come in closed form from the least-squares map of the template's in-plane
   coordinates onto the image (:func:`_necker_pair`), and each is polished by
   Levenberg-Marquardt over its rotation and scale (:func:`_polish_pose`).
3. **Template update.** Given every frame's better pose, each joint's template position is
   the least-squares point its image points agree on (Huber weights, a ridge toward the
   previous position for directions no frame observes), then each joint goes back onto
   the sphere of its known bone length: the lengths fix the template's size and keep it
   from stretching along the viewing direction. Steps 2-3 alternate
   (:func:`fit_template`), accelerated by extrapolation.

Whether the frames determine the template is measured by :func:`information_ratio`: a
still hand seen from one direction does not. Each frame's two poses, with their
reprojection residuals, are then the palm's two tilt states
(:mod:`handdb.lifting.palm_states`).

The pose fits and the template update run in compiled kernels (:mod:`handdb.compiled`),
one frame at a time; the pose fit's steps are inlined into its frame loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from handdb.compiled import inline_kernel, kernel

#: Frames of the clip that inform the template, evenly spread: its 3(K - 1) unknowns are
#: overdetermined many times by a few hundred frames, and the rest of a long clip only
#: costs time. The poses of every frame are fitted with the finished template.
TEMPLATE_FRAMES = 256

#: Accelerated cycles of pose fits and template updates, at most (three alternations
#: each).
TEMPLATE_CYCLES = 12

#: The template counts as settled when no joint moved more than this share of the palm's
#: size in one alternation.
TEMPLATE_TOLERANCE = 1e-5

#: Procrustes passes that align the start's per-frame point sets to their median.
START_PASSES = 4

#: Levenberg-Marquardt iterations polishing each closed-form pose, at most; a pose of a
#: near-planar template starts within a few degrees of its optimum.
POSE_ITERATIONS = 4

#: A polished pose counts as converged when its step is below this (radians, and relative
#: scale).
POSE_STEP_TOLERANCE = 1e-9

#: Starting Levenberg-Marquardt damping, and its factors after a step that lowered the
#: residual and after one that did not.
DAMPING_START = 1e-3
DAMPING_DOWN, DAMPING_UP = 0.3, 10.0

#: Image residual beyond which a joint's weight in the template update falls as 1/residual
#: (Huber), pixels: a mistracked joint in a few frames must not bend the palm.
HUBER_PX = 3.0

#: Ridge of the template update toward each joint's previous position, as a share of the
#: trace of its normal matrix: a direction no frame observes stays where it was.
TEMPLATE_RIDGE = 1e-3

#: Fewest visible palm joints that fix a pose.
MIN_POSE_JOINTS = 3


@dataclass(frozen=True)
class Tilts:
    """Both poses of the template in every frame.

    Attributes
    ----------
    rotation
        ``(T, 2, 3, 3) float64``: template to camera frame, the better-fitting first.
    scale
        ``(T, 2) float64``, pixels per clip unit.
    residual
        ``(T, 2) float64``, pixels: root mean square image distance over the visible palm
        joints; NaN where fewer than :data:`MIN_POSE_JOINTS` are visible.
    """

    rotation: np.ndarray
    scale: np.ndarray
    residual: np.ndarray


def plane_basis(template: np.ndarray) -> np.ndarray:
    """Orthonormal axes of a template's best-fitting plane, ``(3, 3)``, columns ``e1, e2, n``.

    ``template`` is ``(K, 3)``; the axes form a right-handed frame.
    """
    centred = template - template.mean(axis=0)
    basis = np.linalg.svd(centred, full_matrices=True)[2].T
    if np.linalg.det(basis) < 0:
        basis = basis * np.array([1.0, 1.0, -1.0])
    return basis


def fit_tilts(points: np.ndarray, template: np.ndarray) -> Tilts:
    """Fit both poses of the template to every frame.

    Parameters
    ----------
    points
        ``(T, K, 2) float64``, pixels: image points of the palm joints (template order);
        NaN where a joint is missing.
    template
        ``(K, 3) float64``, clip units.

    Returns
    -------
    Tilts
    """
    n_frames = len(points)
    tilts = Tilts(rotation=np.empty((n_frames, 2, 3, 3)), scale=np.empty((n_frames, 2)),
                  residual=np.empty((n_frames, 2)))
    _fit_tilts(points, template, plane_basis(template), tilts.rotation, tilts.scale,
               tilts.residual)
    return tilts


@kernel
def _fit_tilts(points, template, basis, rotation, scale, residual):
    """Fill :class:`Tilts`' arrays, frame by frame; see :func:`fit_tilts`."""
    n_frames, n_joints, _ = points.shape
    weight = np.empty(n_joints)
    centred = np.empty((n_joints, 2))
    shape = np.empty((n_joints, 3))
    pair = np.empty((2, 3, 3))
    scratch = np.empty((8, 4, 4))
    for t in range(n_frames):
        visible = 0
        for k in range(n_joints):
            ok = not (math.isnan(points[t, k, 0]) or math.isnan(points[t, k, 1]))
            weight[k] = 1.0 if ok else 0.0
            visible += 1 if ok else 0
        if visible < MIN_POSE_JOINTS:
            rotation[t] = np.nan
            scale[t] = np.nan
            residual[t] = np.nan
            continue
        _centre(points[t], template, weight, centred, shape)
        start_scale = _necker_pair(centred, shape, weight, basis, pair, scratch[0])
        for h in range(2):
            rotation[t, h] = pair[h]
            scale[t, h] = start_scale
            residual[t, h] = _polish_pose(centred, shape, weight, rotation[t, h],
                                          scale[t, h:h + 1], scratch)
        if residual[t, 1] < residual[t, 0]:
            for i in range(3):
                for j in range(3):
                    rotation[t, 0, i, j], rotation[t, 1, i, j] = (rotation[t, 1, i, j],
                                                                  rotation[t, 0, i, j])
            scale[t, 0], scale[t, 1] = scale[t, 1], scale[t, 0]
            residual[t, 0], residual[t, 1] = residual[t, 1], residual[t, 0]


@inline_kernel
def _centre(points, template, weight, centred, shape):
    """Image points and template about their weighted centroids (``centred``, ``shape``)."""
    total = mean_u = mean_v = mean_x = mean_y = mean_z = 0.0
    for k in range(len(weight)):
        if weight[k] == 0.0:
            continue
        total += weight[k]
        mean_u += weight[k] * points[k, 0]
        mean_v += weight[k] * points[k, 1]
        mean_x += weight[k] * template[k, 0]
        mean_y += weight[k] * template[k, 1]
        mean_z += weight[k] * template[k, 2]
    for k in range(len(weight)):
        seen = weight[k] > 0.0
        centred[k, 0] = points[k, 0] - mean_u / total if seen else 0.0
        centred[k, 1] = points[k, 1] - mean_v / total if seen else 0.0
        shape[k, 0] = template[k, 0] - mean_x / total
        shape[k, 1] = template[k, 1] - mean_y / total
        shape[k, 2] = template[k, 2] - mean_z / total


@inline_kernel
def _necker_pair(centred, shape, weight, basis, pair, rows):
    """Both scaled-orthographic poses of a near-planar template in closed form.

    With ``a`` the joints' in-plane coordinates (axes ``basis[:, 0:2]``), the
    least-squares map ``B`` (2x2) of ``a`` onto the image has rows ``b1, b2``; a scaled
    rotation's first two rows are ``(b1, c1) / s`` and ``(b2, c2) / s`` in the plane's
    frame, with ``c1 = ±sqrt(u)``, ``c2 = ∓sign(b1·b2) sqrt(u − D)``,
    ``D = |b2|² − |b1|²``, ``u = (D + sqrt(D² + 4 (b1·b2)²)) / 2`` and
    ``s = sqrt(|b1|² + u)``: the two signs are the two tilts. Writes the two rotations
    (template to camera) to ``pair`` ``(2, 3, 3)`` and returns ``s``; ``rows`` ``(4, 4)``
    is scratch space.
    """
    m00 = m01 = m11 = 0.0
    x00 = x01 = x10 = x11 = 0.0
    for k in range(len(weight)):
        if weight[k] == 0.0:
            continue
        a0 = shape[k, 0] * basis[0, 0] + shape[k, 1] * basis[1, 0] + shape[k, 2] * basis[2, 0]
        a1 = shape[k, 0] * basis[0, 1] + shape[k, 1] * basis[1, 1] + shape[k, 2] * basis[2, 1]
        m00 += a0 * a0
        m01 += a0 * a1
        m11 += a1 * a1
        x00 += centred[k, 0] * a0
        x01 += centred[k, 0] * a1
        x10 += centred[k, 1] * a0
        x11 += centred[k, 1] * a1
    det = m00 * m11 - m01 * m01
    b11 = (x00 * m11 - x01 * m01) / det
    b12 = (x01 * m00 - x00 * m01) / det
    b21 = (x10 * m11 - x11 * m01) / det
    b22 = (x11 * m00 - x10 * m01) / det
    d12 = b11 * b21 + b12 * b22
    spread = (b21 * b21 + b22 * b22) - (b11 * b11 + b12 * b12)
    u = 0.5 * (spread + math.sqrt(spread * spread + 4.0 * d12 * d12))
    c1 = math.sqrt(max(u, 0.0))
    c2 = -math.copysign(1.0, d12) * math.sqrt(max(u - spread, 0.0))
    s = math.sqrt(b11 * b11 + b12 * b12 + u)
    p, q, r = rows[0], rows[1], rows[2]
    for h in range(2):
        sign = 1.0 if h == 0 else -1.0
        p[0], p[1], p[2] = b11 / s, b12 / s, sign * c1 / s
        q[0], q[1], q[2] = b21 / s, b22 / s, sign * c2 / s
        along = p[0] * q[0] + p[1] * q[1] + p[2] * q[2]
        for a in range(3):
            q[a] -= along * p[a]
        norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
        for a in range(3):
            q[a] /= norm
        r[0] = p[1] * q[2] - p[2] * q[1]
        r[1] = p[2] * q[0] - p[0] * q[2]
        r[2] = p[0] * q[1] - p[1] * q[0]
        for j in range(3):
            pair[h, 0, j] = p[0] * basis[j, 0] + p[1] * basis[j, 1] + p[2] * basis[j, 2]
            pair[h, 1, j] = q[0] * basis[j, 0] + q[1] * basis[j, 1] + q[2] * basis[j, 2]
            pair[h, 2, j] = r[0] * basis[j, 0] + r[1] * basis[j, 1] + r[2] * basis[j, 2]
    return s


@inline_kernel
def _pose_cost(centred, shape, weight, rotation, s):
    """Summed squared image residual of a pose, pixels²."""
    cost = 0.0
    for k in range(len(weight)):
        if weight[k] == 0.0:
            continue
        for a in range(2):
            projected = (rotation[a, 0] * shape[k, 0] + rotation[a, 1] * shape[k, 1]
                         + rotation[a, 2] * shape[k, 2])
            e = centred[k, a] - s * projected
            cost += weight[k] * e * e
    return cost


@inline_kernel
def _polish_pose(centred, shape, weight, rotation, scale, scratch):
    """Levenberg-Marquardt over a pose's rotation (left increment) and scale, in place.

    ``rotation`` ``(3, 3)`` and ``scale`` ``(1,)`` are updated; returns the root mean
    square image residual per visible joint, pixels. ``weight`` is 1 for a visible joint
    and 0 otherwise, so visible joints enter the normal equations unweighted, and only
    their lower triangle is formed: it is all :func:`_solve_spd4` reads. ``scratch``
    ``(8, 4, 4)`` is work space.
    """
    s = scale[0]
    cost = _pose_cost(centred, shape, weight, rotation, s)
    damping = DAMPING_START
    normal, low = scratch[1], scratch[2]
    gradient, step, jac, posed = scratch[3, 0], scratch[3, 1], scratch[3, 2], scratch[3, 3]
    turn, trial = scratch[4, :3, :3], scratch[5, :3, :3]
    for _ in range(POSE_ITERATIONS):
        normal[:] = 0.0
        gradient[:] = 0.0
        for k in range(len(weight)):
            if weight[k] == 0.0:
                continue
            for a in range(3):
                posed[a] = (rotation[a, 0] * shape[k, 0] + rotation[a, 1] * shape[k, 1]
                            + rotation[a, 2] * shape[k, 2])
            for a in range(2):
                # d residual / d (rotation increment, scale): s [P]x row a, and -P_a.
                if a == 0:
                    jac[0], jac[1], jac[2] = 0.0, -s * posed[2], s * posed[1]
                else:
                    jac[0], jac[1], jac[2] = s * posed[2], 0.0, -s * posed[0]
                jac[3] = -posed[a]
                e = centred[k, a] - s * posed[a]
                for i in range(4):
                    gradient[i] += jac[i] * e
                    for j in range(i + 1):
                        normal[i, j] += jac[i] * jac[j]
        for i in range(4):
            normal[i, i] *= 1.0 + damping
        _solve_spd4(normal, gradient, step, low)
        _rotation_vector(-step[0], -step[1], -step[2], turn)
        for i in range(3):
            for j in range(3):
                trial[i, j] = (turn[i, 0] * rotation[0, j] + turn[i, 1] * rotation[1, j]
                               + turn[i, 2] * rotation[2, j])
        trial_s = s - step[3]
        trial_cost = _pose_cost(centred, shape, weight, trial, trial_s)
        size = abs(step[0]) + abs(step[1]) + abs(step[2]) + abs(step[3]) / abs(s)
        if trial_cost < cost:
            rotation[:] = trial
            s, cost = trial_s, trial_cost
            damping *= DAMPING_DOWN
        else:
            damping *= DAMPING_UP
        if size < POSE_STEP_TOLERANCE:
            break
    scale[0] = s
    visible = 0.0
    for k in range(len(weight)):
        visible += weight[k]
    return math.sqrt(cost / visible)


@inline_kernel
def _solve_spd4(matrix, rhs, out, low):
    """Solve the symmetric positive-definite 4x4 ``matrix @ out = rhs`` (Cholesky in ``low``)."""
    for i in range(4):
        for j in range(i + 1):
            total = matrix[i, j]
            for k in range(j):
                total -= low[i, k] * low[j, k]
            if i == j:
                low[i, i] = math.sqrt(max(total, 1e-300))
            else:
                low[i, j] = total / low[j, j]
    for i in range(4):
        total = rhs[i]
        for k in range(i):
            total -= low[i, k] * out[k]
        out[i] = total / low[i, i]
    for i in range(3, -1, -1):
        total = out[i]
        for k in range(i + 1, 4):
            total -= low[k, i] * out[k]
        out[i] = total / low[i, i]


@inline_kernel
def _rotation_vector(wx, wy, wz, out):
    """Rotation matrix of the rotation vector ``(wx, wy, wz)`` (Rodrigues) into ``out``."""
    angle = math.sqrt(wx * wx + wy * wy + wz * wz)
    if angle < 1e-12:
        a, b = 1.0, 0.5
    else:
        a, b = math.sin(angle) / angle, (1.0 - math.cos(angle)) / (angle * angle)
    out[0, 0] = 1.0 - b * (wy * wy + wz * wz)
    out[1, 1] = 1.0 - b * (wx * wx + wz * wz)
    out[2, 2] = 1.0 - b * (wx * wx + wy * wy)
    out[0, 1], out[1, 0] = -a * wz + b * wx * wy, a * wz + b * wx * wy
    out[0, 2], out[2, 0] = a * wy + b * wx * wz, -a * wy + b * wx * wz
    out[1, 2], out[2, 1] = -a * wx + b * wy * wz, a * wx + b * wy * wz


def information_ratio(rotation: np.ndarray, scale: np.ndarray) -> float:
    """How well a clip's views determine a template point in 3D, in [0, 1].

    Parameters
    ----------
    rotation
        ``(T, 3, 3) float64``: one pose per frame, consistent over time.
    scale
        ``(T,) float64``, pixels per clip unit.

    Returns
    -------
    float
        ``λ_min / λ_max`` of ``Σ_t A_tᵀ A_t``, ``A_t = s_t Π R_t`` (the image rows of the
        scaled pose): 0 for a single view (the depth of a point is unobserved), larger the
        more the viewing direction turns. Frames without a pose are left out; 0 when none
        has one.
    """
    ok = np.isfinite(scale)
    if not ok.any():
        return 0.0
    rows = scale[ok, None, None] * rotation[ok, :2, :]
    normal = np.einsum("tai,taj->ij", rows, rows)
    eigen = np.linalg.eigvalsh(normal)
    return float(eigen[0] / eigen[-1])


def on_bone_spheres(template: np.ndarray, parents: np.ndarray,
                    lengths: np.ndarray) -> np.ndarray:
    """Put every joint at its bone's length from its parent, keeping its direction.

    Parameters
    ----------
    template
        ``(K, 3) float64``: joint 0 is the root.
    parents
        ``(K,) int64``: each joint's parent among the template's joints, in topological
        order (``-1`` for the root).
    lengths
        ``(K,) float64``: length of the bone ending at each joint, clip units (ignored at
        the root).

    Returns
    -------
    numpy.ndarray
        ``(K, 3) float64``, the root at the origin.
    """
    out = np.zeros(template.shape)
    for k in range(1, len(template)):
        direction = template[k] - template[parents[k]]
        out[k] = out[parents[k]] + lengths[k] * direction / np.linalg.norm(direction)
    return out


def aligned_median(point_sets: np.ndarray) -> np.ndarray:
    """Median shape of point sets after aligning each to it (rotations or reflections).

    Parameters
    ----------
    point_sets
        ``(N, K, 3) float64``, each set about its centroid.

    Returns
    -------
    numpy.ndarray
        ``(K, 3) float64``: after :data:`START_PASSES` passes of orthogonal Procrustes
        alignment of every set to the current median.
    """
    reference = np.median(point_sets, axis=0)
    for _ in range(START_PASSES):
        u, _, vt = np.linalg.svd(np.einsum("nki,kj->nij", point_sets, reference))
        aligned = np.einsum("nki,nij->nkj", point_sets, u @ vt)
        reference = np.median(aligned, axis=0)
    return reference


def sample_frames(n_frames: int, limit: int) -> np.ndarray:
    """At most ``limit`` frame indices spread evenly over ``n_frames``, ``(N,) int64``."""
    if n_frames <= limit:
        return np.arange(n_frames)
    return np.unique(np.linspace(0, n_frames - 1, limit).round().astype(np.int64))


def fit_template(points: np.ndarray, start: np.ndarray, parents: np.ndarray,
                 lengths: np.ndarray) -> np.ndarray:
    """Refine a palm template on the image points of a clip's frames (steps 2-3 above).

    The alternation converges linearly, slowly when the views turn little, so it is
    accelerated by squared extrapolation (SQUAREM, Varadhan and Roland 2008): from two
    alternations ``S1 = F(S0)``, ``S2 = F(S1)`` the step ``S0 − 2α r + α² v``
    (``r = S1 − S0``, ``v = S2 − 2 S1 + S0``, ``α = −|r| / |v|``) is taken and polished by
    one more alternation, unless it fits the image worse than ``S1`` did.

    Parameters
    ----------
    points
        ``(N, K, 2) float64``, pixels: the palm joints' image points in frames that show
        all of them.
    start
        ``(K, 3) float64``, clip units: the starting template, the root at the origin.
    parents, lengths
        As :func:`on_bone_spheres`.

    Returns
    -------
    numpy.ndarray
        ``(K, 3) float64``, clip units, the root at the origin.
    """
    tolerance = TEMPLATE_TOLERANCE * float(np.mean(lengths[1:]))
    centred = points - points.mean(axis=1, keepdims=True)
    template = start
    for _ in range(TEMPLATE_CYCLES):
        first, _ = _alternate(points, centred, template, parents, lengths)
        second, first_fit = _alternate(points, centred, first, parents, lengths)
        r, v = first - template, second - 2.0 * first + template
        alpha = -float(np.linalg.norm(r)) / max(float(np.linalg.norm(v)), np.finfo(float).tiny)
        alpha = min(alpha, -1.0)
        leap = template - 2.0 * alpha * r + alpha**2 * v
        leap = on_bone_spheres(leap - leap[0], parents, lengths)
        polished, leap_fit = _alternate(points, centred, leap, parents, lengths)
        updated = polished if leap_fit <= first_fit else second
        moved = float(np.max(np.abs(updated - template)))
        template = updated
        if moved < tolerance:
            break
    return template


def _alternate(points: np.ndarray, centred: np.ndarray, template: np.ndarray,
               parents: np.ndarray, lengths: np.ndarray) -> tuple[np.ndarray, float]:
    """One alternation: every frame's better pose, then the template they agree on.

    ``points`` and ``centred`` are ``(N, K, 2)`` pixels (the latter about each frame's
    centroid). Returns the updated template ``(K, 3)`` and the mean image residual of
    ``template``'s poses, pixels.
    """
    tilts = fit_tilts(points, template)
    ok = np.isfinite(tilts.residual[:, 0])
    solved = _agreed_points(centred, tilts.rotation, tilts.scale, ok,
                            template - template.mean(axis=0))
    return (on_bone_spheres(solved - solved[0], parents, lengths),
            float(np.mean(tilts.residual[ok, 0])))


@kernel
def _agreed_points(centred, rotation, scale, ok, shape):
    """Each joint's least-squares template point from its image points in every posed frame.

    ``centred`` ``(N, K, 2)`` pixels; ``rotation`` ``(N, 2, 3, 3)`` and ``scale``
    ``(N, 2)`` are :class:`Tilts`' (the better pose is used), ``ok`` ``(N,)`` the frames
    that have one; ``shape`` ``(K, 3)`` is the template about its centroid. A joint's
    image residual beyond :data:`HUBER_PX` lowers its weight as 1/residual; the ridge
    (:data:`TEMPLATE_RIDGE`) pulls toward ``shape``. Returns ``(K, 3)``, clip units.
    """
    n_frames, n_joints, _ = centred.shape
    normal = np.zeros((n_joints, 3, 3))
    moment = np.zeros((n_joints, 3))
    rows = np.empty((2, 3))
    tiny = np.finfo(np.float64).tiny
    for t in range(n_frames):
        if not ok[t]:
            continue
        for a in range(2):
            for i in range(3):
                rows[a, i] = scale[t, 0] * rotation[t, 0, a, i]
        for k in range(n_joints):
            squared = 0.0
            for a in range(2):
                # x, z, y: the order numpy's einsum summed the projection in before this
                # kernel, which keeps the templates of earlier builds bit for bit
                e = centred[t, k, a] - (rows[a, 0] * shape[k, 0] + rows[a, 2] * shape[k, 2]
                                        + rows[a, 1] * shape[k, 1])
                squared += e * e
            weight = min(1.0, HUBER_PX / max(math.sqrt(squared), tiny))
            for a in range(2):
                for i in range(3):
                    moment[k, i] += weight * rows[a, i] * centred[t, k, a]
                    for j in range(3):
                        normal[k, i, j] += weight * rows[a, i] * rows[a, j]
    solved = np.empty((n_joints, 3))
    for k in range(n_joints):
        ridge = TEMPLATE_RIDGE * (normal[k, 0, 0] + normal[k, 1, 1] + normal[k, 2, 2]) / 3.0
        for i in range(3):
            normal[k, i, i] += ridge
            moment[k, i] += ridge * shape[k, i]
        solved[k] = np.linalg.solve(normal[k], moment[k])
    return solved
