"""The thumb's base: where it sits off the palm is one unknown of the whole clip.

The thumb's carpometacarpal joint does not lie in the plane of the wrist and the long
fingers' knuckles: annotations put it anywhere from that plane to a seventh of the hand's
length in front of it (:data:`handdb.hand.population.THUMB_BASE_HEIGHT_RANGE`), and a
plane fitted through all of them tilts toward it. Its height over the plane of the rigid
palm (:mod:`handdb.lifting.palm_template`), palmar positive, is constant for a rigid
hand, so it is estimated once per clip rather than assumed:

- In every frame and palm tilt the thumb base's bone has two depth signs, so two heights
  ``h₊, h₋`` (:func:`plane_heights`).
- The clip's height ``ĥ`` and spread ``σ`` maximise
  ``Σ_t log(½ N(h₊; ĥ, σ) + ½ N(h₋; ĥ, σ) + ε) + log p(ĥ)``, a mixture over each frame's
  unknown sign with a small outlier floor ``ε``, under a broad prior ``p``
  (:func:`clip_heights`). ``σ`` comes from a short grid: the spread a clip's own heights
  show (tracking noise, a non-rigid tracker palm).
- In a nearly still view each frame's two heights form two clusters equally tight, so the
  likelihood has two modes the data cannot tell apart; both are returned, for the caller
  to compare on the whole solution.

Heights are in palm lengths (the bone from the root to the middle finger's MCP joint), so
that the prior does not depend on the clip's units; at the average hand's 83-mm palm a
palm length of 0.012 is 1 mm.
"""

from __future__ import annotations

import math

import numpy as np

from handdb.compiled import kernel

#: Prior of the thumb base's height, palm lengths: mean and standard deviation (10 and 15
#: mm at the average hand). Broad, and palmar of the plane: annotations put the base from
#: on the plane to about 25 mm in front of it.
HEIGHT_PRIOR = (0.12, 0.18)

#: The clip heights searched, palm lengths (-40 to 40 mm in 0.5-mm steps at the average
#: hand).
HEIGHT_GRID = np.linspace(-0.48, 0.48, 161)

#: Spreads of one frame's height about the clip's tried, palm lengths (1.5 to 9 mm).
SPREAD_GRID = np.array([0.018, 0.024, 0.036, 0.048, 0.072, 0.109])

#: Share of frames whose height may be anything within the grid (mis-tracked frames).
OUTLIER_SHARE = 0.02

#: A second mode of the clip's likelihood counts when it lies this many spreads from the
#: first.
MODE_SEPARATION = 4.0

#: Frames that inform the clip's height, evenly spread: one number is settled by a few
#: thousand frames, and the rest of a long clip only costs time.
HEIGHT_FRAMES = 2048


def log_prior(height: np.ndarray | float) -> np.ndarray:
    """Log density of :data:`HEIGHT_PRIOR` up to a constant, nats; same shape as ``height``."""
    mean, sd = HEIGHT_PRIOR
    return -0.5 * ((np.asarray(height, dtype=np.float64) - mean) / sd) ** 2


def log_normal(x: np.ndarray, mean: np.ndarray | float, sd: np.ndarray | float) -> np.ndarray:
    """Log density of ``N(mean, sd²)`` at ``x``, nats, broadcasting the three."""
    return -0.5 * ((x - mean) / sd) ** 2 - np.log(sd * math.sqrt(2.0 * math.pi))


def outlier_density() -> float:
    """Density of an outlier height over :data:`HEIGHT_GRID`, per palm length."""
    return OUTLIER_SHARE / float(HEIGHT_GRID[-1] - HEIGHT_GRID[0])


def plane_heights(palm: np.ndarray, options: np.ndarray, corners: np.ndarray,
                  handedness: float) -> np.ndarray:
    """Height of each thumb-base option over its frame's palm plane, palmar positive.

    Parameters
    ----------
    palm
        ``(T, 2, K, 3) float64``, clip units: the rigid palm's joints in both palm tilts;
        NaN where missing.
    options
        ``(2, T, 2, 3) float64``, clip units: the thumb base under each sign of its bone
        (deeper first), in both tilts.
    corners
        ``(3,) int64``: where the wrist, index MCP and little MCP are among the ``K``
        joints; ``handedness ((index − wrist) × (little − wrist))`` points to the palmar
        side.
    handedness
        ``+1`` for a right hand, ``−1`` for a left one.

    Returns
    -------
    numpy.ndarray
        ``(2, T, 2) float64``, clip units: distance from the least-squares plane through
        the visible rigid joints; NaN where fewer than three are visible.
    """
    heights = np.empty(options.shape[:3])
    _plane_heights(palm, options, corners, handedness, heights)
    return heights


@kernel
def _plane_heights(palm, options, corners, handedness, heights):
    """Fill ``heights`` ``(2, T, 2)``; see :func:`plane_heights`."""
    n_frames, n_states, n_joints, _ = palm.shape
    scatter = np.empty((3, 3))
    centre, normal, across, along = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    for t in range(n_frames):
        for p in range(n_states):
            points = palm[t, p]
            count = 0
            centre[:] = 0.0
            for k in range(n_joints):
                if not math.isnan(points[k, 0] + points[k, 1] + points[k, 2]):
                    count += 1
                    for a in range(3):
                        centre[a] += points[k, a]
            if count < 3:
                heights[:, t, p] = np.nan
                continue
            for a in range(3):
                centre[a] /= count
            scatter[:] = 0.0
            for k in range(n_joints):
                if not math.isnan(points[k, 0] + points[k, 1] + points[k, 2]):
                    for a in range(3):
                        for b in range(3):
                            scatter[a, b] += ((points[k, a] - centre[a])
                                              * (points[k, b] - centre[b]))
            _least_axis(scatter, normal)
            wrist, index, little = points[corners[0]], points[corners[1]], points[corners[2]]
            for a in range(3):
                across[a] = index[a] - wrist[a]
                along[a] = little[a] - wrist[a]
            side = handedness * (normal[0] * (across[1] * along[2] - across[2] * along[1])
                                 + normal[1] * (across[2] * along[0] - across[0] * along[2])
                                 + normal[2] * (across[0] * along[1] - across[1] * along[0]))
            if side < 0:
                for a in range(3):
                    normal[a] = -normal[a]
            for sign in range(2):
                heights[sign, t, p] = ((options[sign, t, p, 0] - centre[0]) * normal[0]
                                       + (options[sign, t, p, 1] - centre[1]) * normal[1]
                                       + (options[sign, t, p, 2] - centre[2]) * normal[2])


@kernel
def _least_axis(scatter, out):
    """Unit eigenvector of the symmetric 3x3 ``scatter``'s smallest eigenvalue, into ``out``.

    The eigenvalue by the trigonometric solution of the characteristic cubic; the vector
    as the largest cross product of two rows of ``scatter − λ I``.
    """
    q = (scatter[0, 0] + scatter[1, 1] + scatter[2, 2]) / 3.0
    off = scatter[0, 1] ** 2 + scatter[0, 2] ** 2 + scatter[1, 2] ** 2
    p = math.sqrt(((scatter[0, 0] - q) ** 2 + (scatter[1, 1] - q) ** 2
                   + (scatter[2, 2] - q) ** 2 + 2.0 * off) / 6.0)
    if p == 0.0:
        out[0], out[1], out[2] = 0.0, 0.0, 1.0
        return
    b00, b11, b22 = (scatter[0, 0] - q) / p, (scatter[1, 1] - q) / p, (scatter[2, 2] - q) / p
    b01, b02, b12 = scatter[0, 1] / p, scatter[0, 2] / p, scatter[1, 2] / p
    half_det = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
                      + b02 * (b01 * b12 - b11 * b02))
    angle = math.acos(min(max(half_det, -1.0), 1.0)) / 3.0
    least = q + 2.0 * p * math.cos(angle + 2.0 * math.pi / 3.0)
    shifted = scatter.copy()
    for a in range(3):
        shifted[a, a] -= least
    best = -1.0
    for i, j in ((0, 1), (0, 2), (1, 2)):
        first, second = shifted[i], shifted[j]
        cx = first[1] * second[2] - first[2] * second[1]
        cy = first[2] * second[0] - first[0] * second[2]
        cz = first[0] * second[1] - first[1] * second[0]
        norm = cx * cx + cy * cy + cz * cz
        if norm > best:
            best = norm
            out[0], out[1], out[2] = cx, cy, cz
    norm = math.sqrt(best)
    for a in range(3):
        out[a] /= norm


def clip_heights(heights: np.ndarray) -> tuple[list[float], float]:
    """The clip's thumb-base height: the likelihood's modes and the spread chosen.

    Parameters
    ----------
    heights
        ``(2, T) float64``, palm lengths: each frame's two heights (its palm tilt
        chosen); NaN where unknown. At most :data:`HEIGHT_FRAMES` frames, evenly spread,
        are used.

    Returns
    -------
    modes
        Palm lengths: the most likely height, then the strongest other peak at least
        :data:`MODE_SEPARATION` spreads away, if any.
    spread
        The spread (palm lengths) of :data:`SPREAD_GRID` under which the likelihood peaks
        highest.
    """
    known = np.flatnonzero(np.isfinite(heights).all(axis=0))
    if len(known) == 0:
        return [HEIGHT_PRIOR[0]], float(SPREAD_GRID[-1])
    pick = known[np.unique(np.linspace(0, len(known) - 1, min(len(known), HEIGHT_FRAMES))
                           .round().astype(np.int64))]
    curves = np.empty((len(HEIGHT_GRID), len(SPREAD_GRID)))
    _mixture_log_likelihood(np.ascontiguousarray(heights[:, pick]), HEIGHT_GRID,
                            SPREAD_GRID, outlier_density(), curves)
    curves += log_prior(HEIGHT_GRID)[:, None]                            # (H, S)
    best = np.unravel_index(np.argmax(curves), curves.shape)
    spread = float(SPREAD_GRID[best[1]])
    curve = curves[:, best[1]]
    modes = [float(HEIGHT_GRID[best[0]])]
    inner = curve[1:-1]
    peaks = 1 + np.flatnonzero((inner >= curve[:-2]) & (inner >= curve[2:]))
    for peak in peaks[np.argsort(-curve[peaks], kind="stable")]:
        if abs(HEIGHT_GRID[peak] - modes[0]) > MODE_SEPARATION * spread:
            modes.append(float(HEIGHT_GRID[peak]))
            break
    return modes, spread


@kernel
def _mixture_log_likelihood(heights, grid, spreads, floor, out):
    """Fill ``out`` ``(H, S)`` with the mixture's log-likelihood per clip height and spread.

    ``Σ_n log(½ N(h₊ₙ; grid[i], spreads[s]) + ½ N(h₋ₙ; ...) + floor)`` over the ``(2, N)``
    ``heights``; see :func:`clip_heights`. A frame both of whose log densities are below
    :func:`_negligible_log_density` adds ``log(floor)`` without its two exponentials: its
    density is below half a unit in the last place of ``floor``, so ``density + floor``
    rounds to ``floor`` and the sum is the same to the last bit.
    """
    n_points = heights.shape[1]
    log_floor = math.log(floor)
    negligible = _negligible_log_density(floor)
    for i in range(grid.shape[0]):
        for s in range(spreads.shape[0]):
            sd = spreads[s]
            log_norm = math.log(sd * math.sqrt(2.0 * math.pi))
            total = 0.0
            for n in range(n_points):
                above = (heights[0, n] - grid[i]) / sd
                below = (heights[1, n] - grid[i]) / sd
                log_above = -0.5 * above * above - log_norm
                log_below = -0.5 * below * below - log_norm
                if log_above < negligible and log_below < negligible:
                    total += log_floor
                    continue
                density = 0.5 * (math.exp(log_above) + math.exp(log_below))
                total += math.log(density + floor)
            out[i, s] = total


@kernel
def _negligible_log_density(floor):
    """Log density below which a frame's mixture density cannot change ``density + floor``.

    ``floor`` (``> 0``) has a unit in the last place of at least ``floor · 2⁻⁵³``; a
    density below ``floor · 2⁻⁵⁴`` (half of it) rounds away. The bound is taken a factor
    ``e`` lower, for the rounding of ``exp`` and of the half-sum of the two densities.
    Returns ``-inf`` (nothing is negligible) when ``floor`` is not positive.
    """
    if not floor > 0.0:
        return -math.inf
    return math.log(floor) - 54.0 * math.log(2.0) - 1.0
