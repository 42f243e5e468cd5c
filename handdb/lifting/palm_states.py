"""The palm's two tilt states in every frame, from the rigid template or per-frame planes.

The default method (:mod:`handdb.lifting.kinematic`) chooses, frame by frame, between two
states of the palm without the thumb (the *rigid palm*: the root, a palm centre, the long
fingers' MCP joints), then hangs the thumb's base and the fingers from it:

- **Template** (orthographic clips that move): the rigid palm's shape recovered from the
  track (:mod:`handdb.lifting.palm_template`) in its two poses per frame. The pose that
  reprojects better is the likelier one (:func:`residual_evidence`); the frame's scale is
  the pose's, the palm's depths are the pose's.
- **Plane fit** (short or still clips, whose views do not determine a template, and
  pinhole clips): the sign pattern of the palm's bones whose joints fit a plane best
  (:func:`handdb.lifting.palm.palm_signs`), and its mirror image. Through a pinhole the
  joints are then walked along their rays from the root's depth.

Both give :class:`PalmStates`. With the thumb's base left out of the plane, its height off
the plane can be estimated (:mod:`handdb.lifting.thumb_base`) rather than assumed zero.

A palm facing the camera looks the same tilted either way by a few degrees, and its
fingers cannot tell (the palm normal's depth component does not change); what tells is
the transverse arch of the metacarpal heads (:func:`arch_log_odds`): the middle and ring
knuckles lie dorsal of the plane of the wrist and the index and little knuckles
(:data:`handdb.hand.anatomy.METACARPAL_ELEVATION_DEG`), on the other side in the mirror
image.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d, median_filter

from handdb.clip import finite_points
from handdb.compiled import kernel
from handdb.hand.anatomy import MEAN_HAND_LENGTH_MM
from handdb.hand.layout import HandLayout, hand_layout, palm_normals
from handdb.hand.population import KNUCKLE_HEIGHT_SPREAD
from handdb.hand.shape import mean_shape
from handdb.hand.skeletons import Skeleton
from handdb.lifting.geometry import accumulate_depths
from handdb.lifting.palm import palm_signs
from handdb.lifting.palm_template import (
    TEMPLATE_FRAMES,
    aligned_median,
    fit_template,
    fit_tilts,
    information_ratio,
    on_bone_spheres,
    sample_frames,
)
from handdb.lifting.pinhole import walk_rays
from handdb.lifting.temporal import SCALE_SMOOTHING_FRAMES

#: Fewest frames (showing the whole rigid palm) a template is recovered from.
MIN_TEMPLATE_FRAMES = 10

#: Least :func:`~handdb.lifting.palm_template.information_ratio` of the clip's views for
#: the template to be used: below it the views turn too little to fix the palm's depth
#: shape.
MIN_INFORMATION = 0.01

#: Image noise assumed at least in the palm's residual evidence, pixels.
PALM_NOISE_FLOOR_PX = 1.0

#: Weight of the palm's residual evidence (its log-likelihood ratio of the two poses), and
#: the most a frame's evidence may say, nats: the residuals are not independent Gaussian
#: errors (a tracker's palm is not rigid), so they are discounted and capped.
PALM_EVIDENCE_WEIGHT = 0.5
PALM_EVIDENCE_CAP = 4.0

#: The knuckles whose height over the plane of the wrist and the index and little
#: knuckles shows the transverse arch.
ARCH_JOINTS = ("middle_mcp", "ring_mcp")

#: How far an annotation puts a knuckle off the average hand's arch, palm lengths (the
#: bone from the wrist to the middle knuckle): the population's knuckle-height spread
#: (:data:`handdb.hand.population.KNUCKLE_HEIGHT_SPREAD`, hand lengths) at the average
#: hand's proportions.
ARCH_SPREAD = KNUCKLE_HEIGHT_SPREAD * MEAN_HAND_LENGTH_MM / float(
    np.linalg.norm(mean_shape().point("middle_mcp") - mean_shape().point("wrist")))

#: Frames of the median filter over the template poses' scale, then the standard deviation
#: (frames) of the Gaussian that smooths it: one frame's pose scale follows its noise, and
#: a near-frontal palm's pose is poorly determined, while the hand's distance changes
#: slowly (as :data:`handdb.lifting.temporal.SCALE_SMOOTHING_FRAMES`).
POSE_SCALE_FRAMES = 5
POSE_SCALE_SMOOTHING_FRAMES = SCALE_SMOOTHING_FRAMES


@dataclass(frozen=True)
class PalmParts:
    """The rigid palm and the thumb's base of a skeleton.

    Attributes
    ----------
    joints
        ``(K,) int64``: the rigid palm's joints, the root first, in topological order.
    parents
        ``(K,) int64``: each one's parent among them (``-1`` for the root).
    thumb_base
        Joint of the thumb's bone inside the palm, ``-1`` when the thumb hangs from the
        rigid palm itself (``thesis21``).
    thumb_parent
        The rigid palm's joint the thumb base hangs from (``-1`` without a thumb base).
    corners
        ``(3,) int64``: positions of the wrist, index MCP and little MCP in ``joints``.
    arch
        ``(A,) int64``: positions of the knuckles of :data:`ARCH_JOINTS` in ``joints``.
    layout
        The skeleton's :class:`~handdb.hand.layout.HandLayout`.
    rigid
        The same layout with only the rigid palm's bones as palm bones.
    """

    joints: np.ndarray
    parents: np.ndarray
    thumb_base: int
    thumb_parent: int
    corners: np.ndarray
    arch: np.ndarray
    layout: HandLayout
    rigid: HandLayout

    @property
    def bones(self) -> np.ndarray:
        """``(K - 1,) int64``: child joints of the rigid palm's bones."""
        return self.joints[1:]


def palm_parts(skeleton: Skeleton) -> PalmParts:
    """Split a skeleton's palm into its rigid part and the thumb's base.

    Raises
    ------
    SkeletonError
        As :func:`~handdb.hand.layout.hand_layout`.
    """
    layout = hand_layout(skeleton)
    thumb = [j for j in layout.palm_bones if skeleton.fingers[j] == "thumb"]
    rigid_bones = np.array([j for j in layout.palm_bones if j not in thumb], dtype=np.int64)
    joints = np.concatenate([[skeleton.root], rigid_bones]).astype(np.int64)
    where = {int(j): i for i, j in enumerate(joints)}
    parents = np.array([-1] + [where[int(skeleton.parents[j])] for j in rigid_bones],
                       dtype=np.int64)
    corners = np.array([where[layout.wrist], where[layout.index_mcp],
                        where[layout.little_mcp]], dtype=np.int64)
    base = int(thumb[0]) if thumb else -1
    arch = np.array([where[skeleton.index(j)] for j in ARCH_JOINTS], dtype=np.int64)
    return PalmParts(joints=joints, parents=parents, thumb_base=base,
                     thumb_parent=int(skeleton.parents[base]) if thumb else -1,
                     corners=corners, arch=arch, layout=layout,
                     rigid=dataclasses.replace(layout, palm_bones=rigid_bones))


@dataclass(frozen=True)
class PalmStates:
    """The rigid palm's two states in every frame.

    Attributes
    ----------
    points
        ``(T, 2, J, 3) float64``, clip units: the rigid palm's joints in each state
        (other joints NaN). Orthographic: root-relative, ``(x, y) = image / scale``;
        pinhole: camera frame.
    evidence
        ``(T,) float64``, nats: the palm's own log-odds of state 0 over state 1: the two
        poses' residuals (template), the two arches (plane fits).
    scale
        ``(T,) float64``, pixels per clip unit (NaN for a pinhole clip).
    mirrored
        Whether state 1 stands for state 0's mirror image (plane fits; exactly so
        orthographically).
    template
        ``(K, 3) float64``, clip units: the rigid palm's template, ``None`` for plane fits.
    """

    points: np.ndarray
    evidence: np.ndarray
    scale: np.ndarray
    mirrored: bool
    template: np.ndarray | None


def _mean_arch() -> np.ndarray:
    """Heights of the :data:`ARCH_JOINTS` over the average right hand's palm plane.

    ``(A,) float64``, palm lengths, palmar positive: the plane through the wrist, the
    index and the little knuckle of :func:`handdb.hand.shape.mean_shape`.
    """
    shape = mean_shape()
    wrist, index, little = (shape.point(j) for j in ("wrist", "index_mcp", "little_mcp"))
    normal = np.cross(index - wrist, little - wrist)
    normal /= np.linalg.norm(normal)
    size = np.linalg.norm(shape.point("middle_mcp") - wrist)
    return np.array([(shape.point(j) - wrist) @ normal for j in ARCH_JOINTS]) / size


#: :func:`_mean_arch`, the arch knuckles' expected heights, palm lengths.
MEAN_ARCH = _mean_arch()


def arch_heights(palm: np.ndarray, parts: PalmParts, hand: str, size: float) -> np.ndarray:
    """Heights of the arch knuckles over the plane of the wrist, index and little knuckles.

    Parameters
    ----------
    palm
        ``(..., K, 3) float64``, clip units: the rigid palm's joints (``parts.joints``).
    parts
        The skeleton's palm.
    hand
        ``"right"`` or ``"left"``: the palmar side of the plane.
    size
        The palm length, clip units.

    Returns
    -------
    numpy.ndarray
        ``(..., A) float64``, palm lengths, palmar positive; NaN where the wrist and the
        index and little knuckles are collinear or coincide.
    """
    wrist, index, little = (palm[..., c, :] for c in parts.corners)
    # a palm whose corners are collinear has no plane: its heights are NaN, no evidence
    normal = palm_normals(wrist, index, little, hand)
    knuckles = palm[..., parts.arch, :] - wrist[..., None, :]
    return np.einsum("...ai,...i->...a", knuckles, normal) / size


def arch_log_likelihood(heights: np.ndarray) -> np.ndarray:
    """Log-likelihood of arch knuckle heights under the average hand's, nats.

    ``heights`` ``(..., A)`` are :func:`arch_heights`; each is ``N(MEAN_ARCH,
    ARCH_SPREAD²)`` up to a constant. Returns ``heights.shape[:-1]``; NaN counts as none.
    """
    return -0.5 * np.nansum(((heights - MEAN_ARCH) / ARCH_SPREAD) ** 2, axis=-1)


def arch_evidence(palm: np.ndarray, parts: PalmParts, hand: str, size: float) -> np.ndarray:
    """Each frame's log-odds of palm state 0 from the two states' arches, ``(T,)`` nats.

    ``palm`` ``(T, 2, J, 3)``; weighted and capped as the residual evidence
    (:data:`PALM_EVIDENCE_WEIGHT`, :data:`PALM_EVIDENCE_CAP`): a knuckle's annotation is
    off its anatomical place the same way in every frame.
    """
    likelihood = arch_log_likelihood(arch_heights(palm[:, :, parts.joints], parts, hand, size))
    return np.clip(PALM_EVIDENCE_WEIGHT * (likelihood[:, 0] - likelihood[:, 1]),
                   -PALM_EVIDENCE_CAP, PALM_EVIDENCE_CAP)


def template_states(image: np.ndarray, scale: np.ndarray, abs_dz: np.ndarray,
                    skeleton: Skeleton, parts: PalmParts,
                    bone_lengths: np.ndarray) -> PalmStates | None:
    """The palm's two poses per frame from its template, if the clip's views fix one.

    Parameters
    ----------
    image
        ``(T, J, 2) float64``, pixels, orthographic (or weak-perspective) view.
    scale
        ``(T,) float64``, pixels per clip unit: the first scale (eq. 6), for the start.
    abs_dz
        ``(T, J) float64``, clip units: unsigned bone depths at ``scale``.
    skeleton, parts
        The clip's skeleton and its palm.
    bone_lengths
        ``(J,) float64``, clip units.

    Returns
    -------
    PalmStates or None
        ``None`` when fewer than :data:`MIN_TEMPLATE_FRAMES` frames show the whole rigid
        palm or the views fall below :data:`MIN_INFORMATION`. The scale is the poses'.
    """
    points = image[:, parts.joints]                                       # (T, K, 2)
    complete = np.flatnonzero(np.isfinite(points).all(axis=(1, 2)))
    if len(complete) < MIN_TEMPLATE_FRAMES:
        return None
    sample = complete[sample_frames(len(complete), TEMPLATE_FRAMES)]
    lengths = bone_lengths[parts.joints]
    start = _template_start(image[sample] / scale[sample, None, None], abs_dz[sample],
                            skeleton, parts, lengths)
    template = fit_template(points[sample], start, parts.parents, lengths)
    tilts = fit_tilts(points, template)
    depth = np.einsum("thij,kj->thk", tilts.rotation[..., 2:, :], template)  # (T, 2, K)
    order = continuity_order(depth)
    frames = np.arange(len(points))[:, None]
    rotation, depth = tilts.rotation[frames, order], depth[frames, order]
    if information_ratio(rotation[:, 0], tilts.scale[:, 0]) < MIN_INFORMATION:
        return None
    pose_scale = _pose_scale(tilts.scale[:, 0], scale)
    palm = np.full((len(image), 2, skeleton.n_joints, 3), np.nan)
    rel = image[:, parts.joints] - image[:, skeleton.root, None]
    palm[:, :, parts.joints, :2] = (rel / pose_scale[:, None, None])[:, None]
    palm[:, :, parts.joints, 2] = depth
    visible = finite_points(points).sum(axis=1)
    return PalmStates(points=palm, scale=pose_scale, mirrored=False, template=template,
                      evidence=residual_evidence(tilts.residual[frames, order], visible))


def _template_start(xy: np.ndarray, abs_dz: np.ndarray, skeleton: Skeleton,
                    parts: PalmParts, lengths: np.ndarray) -> np.ndarray:
    """Starting template: per-frame plane fits of the rigid palm, aligned and averaged.

    ``xy`` ``(N, J, 2)`` and ``abs_dz`` ``(N, J)`` are clip units; returns ``(K, 3)``
    with the root at the origin and every joint at its bone length.
    """
    signs = palm_signs(xy, abs_dz, skeleton, parts.rigid)
    dz = np.zeros(abs_dz.shape)
    dz[:, parts.bones] = signs * abs_dz[:, parts.bones]
    z = accumulate_depths(dz, skeleton)[:, parts.joints]
    sets = np.concatenate([xy[:, parts.joints], z[..., None]], axis=-1)
    shape = aligned_median(sets - sets.mean(axis=1, keepdims=True))
    return on_bone_spheres(shape - shape[0], parts.parents, lengths)


def _pose_scale(pose: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """The template poses' scale per frame, filtered; ``fallback`` where none."""
    filled = np.where(np.isfinite(pose), pose, fallback)
    return gaussian_filter1d(median_filter(filled, size=POSE_SCALE_FRAMES, mode="nearest"),
                             POSE_SCALE_SMOOTHING_FRAMES, mode="nearest")


def residual_evidence(residual: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """Log-odds of each frame's first pose from the two poses' image residuals.

    Parameters
    ----------
    residual
        ``(T, 2) float64``, pixels: root mean square residual of each pose; NaN where
        none.
    visible
        ``(T,) int64``: joints the residuals are over.

    Returns
    -------
    numpy.ndarray
        ``(T,) float64``, nats: the Gaussian log-likelihood ratio of the poses, with the
        noise set by the clip's median best residual (at least
        :data:`PALM_NOISE_FLOOR_PX`), weighted by :data:`PALM_EVIDENCE_WEIGHT` and capped
        at :data:`PALM_EVIDENCE_CAP`; 0 where unknown.
    """
    best = np.fmin(residual[:, 0], residual[:, 1])                        # NaN: neither
    noise = max(PALM_NOISE_FLOOR_PX, float(np.nanmedian(best))) if np.isfinite(best).any() \
        else PALM_NOISE_FLOOR_PX
    ratio = visible * (residual[:, 1] ** 2 - residual[:, 0] ** 2) / (2.0 * noise**2)
    return np.nan_to_num(np.clip(PALM_EVIDENCE_WEIGHT * ratio, -PALM_EVIDENCE_CAP,
                                 PALM_EVIDENCE_CAP))


def continuity_order(depth: np.ndarray) -> np.ndarray:
    """Order each frame's two states so that state 0 continues the previous frame's.

    Parameters
    ----------
    depth
        ``(T, 2, K) float64``: the palm joints' depths in each state; NaN where unknown.

    Returns
    -------
    numpy.ndarray
        ``(T, 2) int64``: ``depth[t, order[t]]`` puts first the state nearer to the last
        known state 0 (frame 0: as given).
    """
    order = np.empty((len(depth), 2), dtype=np.int64)
    _continuity_order(depth, order)
    return order


@kernel
def _continuity_order(depth, order):
    """Fill ``order`` ``(T, 2)``; see :func:`continuity_order`."""
    n_frames, _, n_joints = depth.shape
    last = -1
    for t in range(n_frames):
        order[t, 0], order[t, 1] = 0, 1
        if last < 0:
            if not np.isnan(depth[t, 0, 0]):
                last = t
            continue
        keep = swap = 0.0
        for k in range(n_joints):
            reference = depth[last, order[last, 0], k]
            keep += (depth[t, 0, k] - reference) ** 2
            swap += (depth[t, 1, k] - reference) ** 2
        if np.isnan(keep + swap):
            continue
        if swap < keep:
            order[t, 0], order[t, 1] = 1, 0
        last = t


def plane_states(xy: np.ndarray, abs_dz: np.ndarray, skeleton: Skeleton, parts: PalmParts,
                 plane: HandLayout, scale: np.ndarray, hand: str, size: float) -> PalmStates:
    """The palm's states from per-frame plane fits, orthographically: a pattern and its mirror.

    Parameters
    ----------
    xy
        ``(T, J, 2) float64``, clip units, image-plane positions.
    abs_dz
        ``(T, J) float64``, clip units, unsigned bone depths.
    skeleton, parts
        The clip's skeleton and its palm.
    plane
        The layout whose palm bones are fitted to a plane: ``parts.rigid``, or the whole
        palm (the thumb's base in the plane too); only the rigid palm's joints are kept.
    scale
        ``(T,) float64``, pixels per clip unit.
    hand, size
        Which hand the clip shows, and its palm length (clip units), for the arch
        evidence (:func:`arch_evidence`).
    """
    signs = palm_signs(xy, abs_dz, skeleton, plane)
    dz = np.zeros(abs_dz.shape)
    dz[:, plane.palm_bones] = signs * abs_dz[:, plane.palm_bones]
    z = accumulate_depths(dz, skeleton)[:, parts.joints]
    palm = np.full((len(xy), 2, skeleton.n_joints, 3), np.nan)
    palm[:, :, parts.joints, :2] = (xy[:, parts.joints] - xy[:, skeleton.root, None])[:, None]
    palm[:, 0, parts.joints, 2] = z
    palm[:, 1, parts.joints, 2] = -z
    return PalmStates(points=palm, evidence=arch_evidence(palm, parts, hand, size), scale=scale,
                      mirrored=True, template=None)


def ray_plane_states(rays: np.ndarray, root_depth: np.ndarray, metric_xy: np.ndarray,
                     abs_dz: np.ndarray, skeleton: Skeleton, parts: PalmParts,
                     plane: HandLayout, bone_lengths: np.ndarray, hand: str,
                     size: float) -> PalmStates:
    """The palm's states through a pinhole: a plane fit's pattern and its mirror, on the rays.

    Parameters
    ----------
    rays
        ``(T, J, 3) float64`` from :func:`handdb.lifting.pinhole.camera_rays`.
    root_depth
        ``(T,) float64``, clip units.
    metric_xy
        ``(T, J, 2) float64``, clip units: ray positions at the root's depth, about the
        root.
    abs_dz
        ``(T, J) float64``, clip units: unsigned bone depths at the root's depth.
    skeleton, parts, plane
        As :func:`plane_states`.
    bone_lengths
        ``(J,) float64``, clip units.
    hand, size
        As :func:`plane_states`.
    """
    signs = palm_signs(metric_xy, abs_dz, skeleton, plane)
    palm_dz = np.full(abs_dz.shape, np.nan)
    palm_dz[:, plane.palm_bones] = signs * abs_dz[:, plane.palm_bones]
    palm = np.full((len(rays), 2, skeleton.n_joints, 3), np.nan)
    for state, sign in enumerate((1.0, -1.0)):
        walked = walk_rays(rays, root_depth, skeleton, bone_lengths, sign * palm_dz)[0]
        palm[:, state, parts.joints] = walked[:, parts.joints]
    return PalmStates(points=palm, evidence=arch_evidence(palm, parts, hand, size),
                      scale=np.full(len(rays), np.nan), mirrored=True, template=None)
