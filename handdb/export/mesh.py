"""A skinned hand mesh: a capsule per finger bone and a rounded palm, posed by skinning.

The mesh is built in the rest pose of :func:`handdb.export.rotations.rest_positions` (a flat hand,
fingers along ``+Y``, thumb towards ``+X``, palm normal ``+Z``), sized from the bone lengths.

Sizes scale with the hand's knuckle span ``W``, the distance between the index and little
MCPs (about 50 mm in an adult hand, whatever the skeleton), not with each finger's own
bones: a skeleton whose little finger or thumb has short bones (``thesis21``) still gets
fingers of a hand's proportions. A finger's capsule radius is :data:`FINGER_RADIUS_RATIO`
of ``W`` times its :data:`FINGER_RADIUS_SCALE` (four fingers side by side then span the
knuckles, as a hand's do). Every finger bone whose parent joint aims at it gets a capsule
bound to that parent joint, blending into the grandparent joint over one radius around
the knuckle so joints bend smoothly.

The palm is the convex hull of spheres of radius :data:`PALM_RADIUS_RATIO` ``W`` (the palm
about ``0.56 W`` thick) around the palm root and its children (wrist, MCPs, thumb base)
and around two heel points beside the wrist, :data:`HEEL_HALF_WIDTH_RATIO` ``W`` to either
side along the palm's ``X``, so the palm keeps its breadth down to the wrist instead of
narrowing to it as a cone; bound rigidly to the root. Each vertex has :data:`INFLUENCES`
joint influences whose weights sum to 1.

Posing uses linear blend skinning with the joint transforms of
:mod:`handdb.export.rotations`, so a posed mesh follows the same skeleton that is exported to USD.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import trimesh

from handdb.export.rotations import (
    child_counts,
    joint_rotations,
    palm_joints,
    rest_pose,
    rest_positions,
    world_transforms,
)
from handdb.hand.skeletons import Skeleton

#: Joint influences per vertex.
INFLUENCES = 2

#: Capsule radius of a finger as a fraction of the knuckle span ``W`` (index to little MCP).
FINGER_RADIUS_RATIO = 1.0 / 6.0

#: Each finger's radius relative to :data:`FINGER_RADIUS_RATIO` (a finger not listed: 1).
FINGER_RADIUS_SCALE = {"thumb": 1.1, "index": 1.0, "middle": 1.0, "ring": 0.95,
                       "little": 0.85}

#: Radius of the palm's spheres (half its thickness) as a fraction of ``W``.
PALM_RADIUS_RATIO = 0.28

#: Distance of each heel point from the wrist, along the palm's ``X``, as a fraction of ``W``.
HEEL_HALF_WIDTH_RATIO = 0.35

#: Rings along and segments around each capsule (trimesh's ``count``).
CAPSULE_COUNT = (10, 8)

#: Least area of a capsule's smallest face, in trimesh's merge tolerances (``tol.merge``,
#: squared units), for its mesh to be computed here rather than by trimesh: nearer that
#: tolerance trimesh's mesh depends on the capsule's size (it drops faces).
CAPSULE_AREA_MARGIN = 100.0

#: Subdivisions of the spheres whose hull makes the palm.
PALM_SPHERE_SUBDIVISIONS = 1


@dataclass(frozen=True)
class HandMesh:
    """A hand mesh in the rest pose with its skinning.

    Attributes
    ----------
    vertices
        ``(V, 3) float64`` rest-pose positions, clip units, in the skeleton's bind space.
    faces
        ``(F, 3) int64`` vertex indices, counter-clockwise seen from outside.
    joint_indices
        ``(V, INFLUENCES) int64`` joints that move each vertex.
    joint_weights
        ``(V, INFLUENCES) float64`` their weights; each row sums to 1.
    face_joints
        ``(F,) int64`` the bone each face belongs to, named by its child joint as bones
        are; the palm's faces carry the root joint.
    """

    vertices: np.ndarray
    faces: np.ndarray
    joint_indices: np.ndarray
    joint_weights: np.ndarray
    face_joints: np.ndarray

    def to_trimesh(self, vertices: np.ndarray | None = None) -> trimesh.Trimesh:
        """Return the mesh (or its faces on ``vertices``) with ``face_attributes['joint']``."""
        return trimesh.Trimesh(
            vertices=self.vertices if vertices is None else vertices,
            faces=self.faces,
            face_attributes={"joint": self.face_joints},
            process=False,
        )


def _capsule_bones(skeleton: Skeleton) -> np.ndarray:
    """Bones ``(B', 2)`` (parent, child) whose parent joint has exactly one child."""
    return skeleton.bones[child_counts(skeleton)[skeleton.bones[:, 0]] == 1]


def knuckle_span(skeleton: Skeleton, rest: np.ndarray) -> float:
    """``W``: the distance between the index and little MCPs of ``rest``, its units.

    Raises
    ------
    SkeletonError
        If the skeleton lacks a wrist or a finger's MCP
        (:func:`handdb.export.rotations.palm_joints`).
    """
    _, mcps = palm_joints(skeleton)
    return float(np.linalg.norm(rest[mcps[0]] - rest[mcps[-1]]))


def finger_radii(skeleton: Skeleton, span: float) -> dict[str, float]:
    """Capsule radius of each finger with capsule bones, ``span`` (``W``) units."""
    fingers = {skeleton.fingers[c] for c in _capsule_bones(skeleton)[:, 1]}
    return {f: FINGER_RADIUS_RATIO * FINGER_RADIUS_SCALE.get(f, 1.0) * span for f in fingers}


@functools.cache
def _ring_directions() -> tuple[np.ndarray, np.ndarray]:
    """The unit profile and the section directions of :func:`_capsule_rings`.

    ``(P, 2) float64`` (cosine, sine) of the profile's angles and ``(S, 2) float64`` of the
    turns about ``+Z``, as trimesh computes them; they depend on :data:`CAPSULE_COUNT`
    alone. Read, never written.
    """
    rings, sections = CAPSULE_COUNT
    theta = np.concatenate((np.linspace(-np.pi / 2.0, 0.0, rings // 2 + 1),
                            np.linspace(0.0, np.pi / 2.0, rings // 2 + 1)))
    turn = np.linspace(0.0, 2.0 * np.pi, sections + 1)[:-1]
    return (np.column_stack((np.cos(theta), np.sin(theta))),
            np.column_stack((np.cos(turn), np.sin(turn))))


def _capsule_rings(length: float, radius: float) -> np.ndarray:
    """A capsule's points along ``+Z`` about the origin, as trimesh computes them.

    The profile (two quarter circles of ``radius``, ``length`` apart) revolved in
    :data:`CAPSULE_COUNT` sections, with the arithmetic of ``trimesh.creation.capsule``
    before it merges the copies of each pole: ``(S P, 3) float64``, ``length`` units, ring
    by ring.
    """
    unit_profile, around = _ring_directions()
    profile = unit_profile * radius
    half = len(profile) // 2
    profile[:half, 1] -= length / 2.0
    profile[half:, 1] += length / 2.0
    points = np.empty((len(around), len(profile), 3))
    points[..., :2] = around[:, None, :] * profile[None, :, 0, None]
    points[..., 2] = profile[:, 1]
    return points.reshape(-1, 3)


@functools.cache
def _capsule_topology() -> tuple[np.ndarray, np.ndarray]:
    """What ``trimesh.creation.capsule`` keeps of :func:`_capsule_rings`, and its faces.

    Returns the indices ``(V,) int64`` of the points it keeps (one of each pole's copies)
    and its faces ``(F, 3) int64`` on them. They depend on :data:`CAPSULE_COUNT` alone,
    not on the capsule's size, so one capsule built by trimesh gives them for all.
    """
    reference = trimesh.creation.capsule(height=1.0, radius=1.0, count=CAPSULE_COUNT)
    rings = _capsule_rings(1.0, 1.0)
    same = (reference.vertices[:, None, :] == rings[None]).all(axis=-1)   # (V, S P)
    return np.argmax(same, axis=1), np.asarray(reference.faces, dtype=np.int64)


def _capsules(starts: np.ndarray, ends: np.ndarray,
              radii: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Capsules whose sphere centres are ``starts`` and ``ends``: each one's vertices and faces.

    The meshes ``trimesh.creation.capsule`` makes, point for point, without building a
    ``Trimesh`` for each (that costs ten times the arithmetic); the smallest faces of all
    of them are measured in one call. A capsule whose smallest face is within
    :data:`CAPSULE_AREA_MARGIN` of trimesh's merge tolerance is left to trimesh, which
    drops faces and merges points at that tolerance.

    Parameters
    ----------
    starts, ends
        ``(B, 3) float64``: the capsules' axis ends, any length unit.
    radii
        ``(B,) float64``, the unit of ``starts``.

    Returns
    -------
    list
        Per capsule, ``(V, 3) float64`` vertices in the unit of ``starts`` and
        ``(F, 3) int64`` faces.
    """
    kept, faces = _capsule_topology()
    placements = []
    for start, end, radius in zip(starts, ends, radii, strict=True):
        axis = end - start
        length = float(np.linalg.norm(axis))
        transform = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis / length)
        transform[:3, 3] = (start + end) / 2
        placed = trimesh.transformations.transform_points(_capsule_rings(length, radius),
                                                          transform)[kept]
        placements.append((placed, transform, length))
    if not placements:
        return []
    triangles = np.concatenate([placed[faces] for placed, _, _ in placements])
    smallest = trimesh.triangles.area(triangles).reshape(len(placements), -1).min(axis=1)
    capsules = []
    for (placed, transform, length), radius, least in zip(placements, radii, smallest,
                                                          strict=True):
        if least > CAPSULE_AREA_MARGIN * trimesh.tol.merge:
            capsules.append((placed, faces))
            continue
        small = trimesh.creation.capsule(height=length, radius=radius, count=CAPSULE_COUNT,
                                         transform=transform)
        capsules.append((small.vertices, np.asarray(small.faces, dtype=np.int64)))
    return capsules


def hand_mesh(skeleton: Skeleton, bone_lengths: np.ndarray) -> HandMesh:
    """Build the skinned capsule hand of ``skeleton`` in its rest pose.

    Parameters
    ----------
    skeleton
        The skeleton; it needs a palm (see :func:`handdb.export.rotations.palm_frame`).
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.

    Returns
    -------
    HandMesh
        A few thousand faces, in clip units.
    """
    rest = rest_positions(skeleton, bone_lengths)
    bones = _capsule_bones(skeleton)
    span = knuckle_span(skeleton, rest)
    radii = finger_radii(skeleton, span)

    parts, indices, weights, face_joints = [], [], [], []
    capsule_radii = np.array([radii[skeleton.fingers[child]] for child in bones[:, 1]])
    capsules = _capsules(rest[bones[:, 0]], rest[bones[:, 1]], capsule_radii)
    for (parent, child), radius, (vertices, faces) in zip(bones, capsule_radii, capsules,
                                                          strict=True):
        direction = (rest[child] - rest[parent]) / bone_lengths[child]
        along = (vertices - rest[parent]) @ direction
        own = np.clip(0.5 + along / (2 * radius), 0.0, 1.0)
        parts.append((vertices, faces))
        indices.append(np.tile([parent, skeleton.parents[parent]], (len(vertices), 1)))
        weights.append(np.stack([own, 1.0 - own], axis=1))
        face_joints.append(np.full(len(faces), child))

    wrist, _ = palm_joints(skeleton)
    heel = rest[wrist] + np.outer([-1.0, 1.0], [HEEL_HALF_WIDTH_RATIO * span, 0.0, 0.0])
    centres = np.concatenate(
        [rest[np.append(skeleton.root, skeleton.children(skeleton.root))], heel])
    sphere = trimesh.creation.icosphere(subdivisions=PALM_SPHERE_SUBDIVISIONS,
                                        radius=PALM_RADIUS_RATIO * span)
    cloud = (centres[:, None, :] + sphere.vertices[None]).reshape(-1, 3)
    palm = trimesh.convex.convex_hull(cloud)
    parts.append((palm.vertices, palm.faces))
    indices.append(np.tile([skeleton.root, skeleton.root], (len(palm.vertices), 1)))
    weights.append(np.tile([1.0, 0.0], (len(palm.vertices), 1)))
    face_joints.append(np.full(len(palm.faces), skeleton.root))

    offsets = np.cumsum([0] + [len(vertices) for vertices, _ in parts[:-1]])
    return HandMesh(
        vertices=np.concatenate([vertices for vertices, _ in parts]),
        faces=np.concatenate(
            [faces + o for (_, faces), o in zip(parts, offsets, strict=True)]).astype(np.int64),
        joint_indices=np.concatenate(indices).astype(np.int64),
        joint_weights=np.concatenate(weights),
        face_joints=np.concatenate(face_joints).astype(np.int64),
    )


def posed_vertices(
    mesh: HandMesh, xyz: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray
) -> np.ndarray:
    """Skin ``mesh`` onto joint positions by linear blend skinning.

    Parameters
    ----------
    mesh
        The rest-pose mesh of ``skeleton`` and ``bone_lengths`` (:func:`hand_mesh`).
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, no NaN.
    skeleton, bone_lengths
        As for :func:`hand_mesh`.

    Returns
    -------
    numpy.ndarray
        ``(T, V, 3) float64`` posed vertices, clip units. The skeleton is posed by
        :func:`handdb.export.rotations.joint_rotations`, so where ``xyz`` disagrees with
        ``bone_lengths`` the mesh follows the bone directions.
    """
    bind_rot, bind_pos = world_transforms(rest_pose(skeleton, bone_lengths), skeleton)
    rot, pos = world_transforms(joint_rotations(xyz, skeleton, bone_lengths), skeleton)
    linear = rot @ np.swapaxes(bind_rot, -1, -2)                          # (T, J, 3, 3)
    shift = pos - np.einsum("tjab,jb->tja", linear, bind_pos[0])          # (T, J, 3)
    per_influence = (
        np.einsum("tvkab,vb->tvka", linear[:, mesh.joint_indices], mesh.vertices)
        + shift[:, mesh.joint_indices]
    )
    return np.einsum("tvka,vk->tva", per_influence, mesh.joint_weights)


def posed_hand_mesh(
    xyz_frame: np.ndarray,
    skeleton: Skeleton,
    bone_lengths: np.ndarray,
    mesh: HandMesh | None = None,
) -> trimesh.Trimesh:
    """Pose the hand mesh at one frame, e.g. for occlusion ray casts (``trimesh.ray``).

    Parameters
    ----------
    xyz_frame
        Joint positions of one frame, ``(J, 3) float64``, clip units.
    skeleton, bone_lengths
        As for :func:`hand_mesh`.
    mesh
        The rest-pose mesh, to reuse across frames; built when ``None``.

    Returns
    -------
    trimesh.Trimesh
        Posed mesh in the frame of ``xyz_frame``; ``face_attributes['joint']`` holds the
        bone of each face (its child joint index; the root for the palm).
    """
    mesh = hand_mesh(skeleton, bone_lengths) if mesh is None else mesh
    vertices = posed_vertices(mesh, np.asarray(xyz_frame)[None], skeleton, bone_lengths)[0]
    return mesh.to_trimesh(vertices)
