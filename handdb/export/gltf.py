"""Export a clip as a skinned glTF 2.0 animation in one binary file (``.glb``, pygltflib).

Layout of the file (``<Hand>`` is ``RightHand`` or ``LeftHand``)::

    scene <clip_id>
      node <Hand>              identity; extras handdb:clipId, handdb:hand, handdb:units
        node <root joint>      the skin's skeleton root, then one node per joint,
          node <child joint>   named by the joint, children under their parents
          ...
        node <Hand>Mesh        the capsule hand of :func:`handdb.export.mesh.hand_mesh`,
                               skinned by the skin (JOINTS_0 / WEIGHTS_0)
    skin <Hand>Skin            joints: every joint node in skeleton order;
                               inverseBindMatrices of the rest pose
    animation <clip_id>        a rotation channel per joint, a translation channel per
                               joint whose translation leaves its rest value (the root's
                               always); LINEAR samplers on one time accessor

Joint transforms are the USD export's (:mod:`handdb.export.usd`):
:func:`handdb.export.rotations.joint_rotations` of the positions, turned Y-up by
:data:`handdb.export.rotations.CAMERA_TO_Y_UP` at the root; the rest pose (each node's
own translation and rotation, and the bind pose) is
:func:`handdb.export.rotations.rest_pose` with the clip's bone lengths. By default the
animation reproduces the positions exactly (a bone takes its measured length in each frame
through its translation); ``keep_lengths=True`` gives every bone its stored length.

Axes and units as glTF requires: Y up, right-handed, metres (clip lengths times the
unit's metres). Frame ``i`` is at ``i / fps`` seconds. Quaternions are ``(x, y, z, w)``,
unit length in float32.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from handdb.clip import METERS_PER_UNIT
from handdb.errors import ParameterError
from handdb.export.clip_checks import check_skinned_clip, require_filled
from handdb.export.mesh import hand_mesh
from handdb.export.rotations import (
    CAMERA_TO_Y_UP,
    JointMotion,
    joint_rotations,
    rest_pose,
    turn_root,
    world_transforms,
)
from handdb.export.staging import staged_file
from handdb.hand.skeletons import Skeleton

if TYPE_CHECKING:
    import pygltflib

GLB_SUFFIX = ".glb"

#: Joint influences per vertex in glTF's ``JOINTS_0`` / ``WEIGHTS_0``.
GLTF_INFLUENCES = 4

#: A translation farther than this from its rest value (metres) is animated.
TRANSLATION_TOLERANCE_M = 1e-9

#: glTF accessor component types and buffer view targets (glTF 2.0, section 5).
FLOAT, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963

_ACCESSOR_TYPES = {1: "SCALAR", 3: "VEC3", 4: "VEC4", 16: "MAT4"}


@dataclass
class _Buffer:
    """The binary chunk being built, with its buffer views and accessors."""

    data: bytearray = field(default_factory=bytearray)
    views: list = field(default_factory=list)
    accessors: list = field(default_factory=list)

    def add(self, values: np.ndarray, component: int, *, target: int | None = None,
            bounds: bool = False) -> int:
        """Append ``values`` (``(N,)`` or ``(N, K)``) as one accessor; return its index."""
        import pygltflib

        dtype = {FLOAT: np.float32, UNSIGNED_SHORT: np.uint16, UNSIGNED_INT: np.uint32}[component]
        values = np.ascontiguousarray(values, dtype=dtype)
        width = 1 if values.ndim == 1 else values.shape[1]
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.views.append(pygltflib.BufferView(buffer=0, byteOffset=len(self.data),
                                               byteLength=values.nbytes, target=target))
        self.data.extend(values.tobytes())
        flat = values.reshape(len(values), width)
        self.accessors.append(pygltflib.Accessor(
            bufferView=len(self.views) - 1, componentType=component, count=len(values),
            type=_ACCESSOR_TYPES[width],
            min=flat.min(axis=0).tolist() if bounds else None,
            max=flat.max(axis=0).tolist() if bounds else None))
        return len(self.accessors) - 1


def _xyzw(wxyz: np.ndarray) -> np.ndarray:
    """Quaternions ``(..., 4)`` scalar first as glTF's ``(x, y, z, w)``, unit in float32."""
    xyzw = np.roll(wxyz, -1, axis=-1).astype(np.float32)
    return xyzw / np.linalg.norm(xyzw, axis=-1, keepdims=True)


def _inverse_binds(rest: JointMotion, skeleton: Skeleton, scale: float) -> np.ndarray:
    """``(J, 16)`` column-major inverse bind matrices of the rest pose, metres."""
    orientations, positions = world_transforms(rest, skeleton)
    inverse = np.zeros((skeleton.n_joints, 4, 4))
    inverse[:, :3, :3] = np.swapaxes(orientations[0], -1, -2)
    inverse[:, :3, 3] = -np.einsum("jab,jb->ja", inverse[:, :3, :3], positions[0] * scale)
    inverse[:, 3, 3] = 1.0
    return np.swapaxes(inverse, -1, -2).reshape(skeleton.n_joints, 16)


def _mesh_accessors(buffer: _Buffer, skeleton: Skeleton, bone_lengths: np.ndarray,
                    scale: float) -> dict[str, int]:
    """Add the skinned hand mesh; return its attribute accessors and ``indices``."""
    hand = hand_mesh(skeleton, bone_lengths)
    vertices = hand.vertices * scale
    normals = trimesh.Trimesh(vertices, hand.faces, process=False).vertex_normals
    joints = np.zeros((len(vertices), GLTF_INFLUENCES), dtype=np.uint16)
    weights = np.zeros((len(vertices), GLTF_INFLUENCES), dtype=np.float32)
    joints[:, :hand.joint_indices.shape[1]] = hand.joint_indices
    weights[:, :hand.joint_weights.shape[1]] = hand.joint_weights
    return {
        "POSITION": buffer.add(vertices, FLOAT, target=ARRAY_BUFFER, bounds=True),
        "NORMAL": buffer.add(normals, FLOAT, target=ARRAY_BUFFER),
        "JOINTS_0": buffer.add(joints, UNSIGNED_SHORT, target=ARRAY_BUFFER),
        "WEIGHTS_0": buffer.add(weights, FLOAT, target=ARRAY_BUFFER),
        "indices": buffer.add(hand.faces.ravel(), UNSIGNED_INT, target=ELEMENT_ARRAY_BUFFER),
    }


def build_clip_gltf(*, clip_id: str, skeleton: Skeleton, motion: JointMotion,
                    bone_lengths: np.ndarray, fps: float, units: str,
                    hand: str) -> pygltflib.GLTF2:
    """Build the glTF document of a clip (see the module doc for its layout).

    Parameters
    ----------
    clip_id
        The clip's id: the scene's and the animation's name.
    skeleton, motion, bone_lengths, fps, units, hand
        As for :func:`handdb.export.usd.build_clip_stage`.

    Returns
    -------
    pygltflib.GLTF2
        The document, its binary chunk set.
    """
    import pygltflib

    scale = METERS_PER_UNIT[units]
    n_joints = skeleton.n_joints
    name = f"{hand.capitalize()}Hand"
    rest = rest_pose(skeleton, bone_lengths)
    animated = turn_root(motion, skeleton, CAMERA_TO_Y_UP)
    buffer = _Buffer()

    nodes = [pygltflib.Node(
        name=joint, translation=(rest.translations[0, j] * scale).tolist(),
        rotation=_xyzw(rest.rotations[0, j]).tolist(),
        children=[int(c) for c in skeleton.children(j)] or None)
        for j, joint in enumerate(skeleton.joints)]
    mesh_node, hand_node = n_joints, n_joints + 1
    attributes = _mesh_accessors(buffer, skeleton, bone_lengths, scale)
    indices = attributes.pop("indices")
    nodes.append(pygltflib.Node(name=f"{name}Mesh", mesh=0, skin=0))
    nodes.append(pygltflib.Node(name=name, children=[skeleton.root, mesh_node], extras={
        "handdb:clipId": clip_id, "handdb:hand": hand, "handdb:units": units}))
    skin = pygltflib.Skin(name=f"{name}Skin", joints=list(range(n_joints)),
                          skeleton=skeleton.root, inverseBindMatrices=buffer.add(
                              _inverse_binds(rest, skeleton, scale), FLOAT))

    times = buffer.add(np.arange(motion.n_frames) / fps, FLOAT, bounds=True)
    samplers, channels = [], []

    def channel(joint: int, path: str, values: np.ndarray) -> None:
        samplers.append(pygltflib.AnimationSampler(input=times, output=buffer.add(
            values, FLOAT), interpolation="LINEAR"))
        channels.append(pygltflib.AnimationChannel(
            sampler=len(samplers) - 1, target=pygltflib.AnimationChannelTarget(
                node=joint, path=path)))

    translations = animated.translations * scale
    moves = np.abs(translations - rest.translations * scale).max(axis=(0, 2))
    for joint in range(n_joints):
        channel(joint, "rotation", _xyzw(animated.rotations[:, joint]))
        if joint == skeleton.root or moves[joint] > TRANSLATION_TOLERANCE_M:
            channel(joint, "translation", translations[:, joint])

    document = pygltflib.GLTF2(
        asset=pygltflib.Asset(version="2.0", generator="handdb"),
        scene=0, scenes=[pygltflib.Scene(name=clip_id, nodes=[hand_node])],
        nodes=nodes, skins=[skin],
        meshes=[pygltflib.Mesh(name=f"{name}Mesh", primitives=[pygltflib.Primitive(
            attributes=pygltflib.Attributes(**attributes), indices=indices)])],
        animations=[pygltflib.Animation(name=clip_id, samplers=samplers, channels=channels)],
        accessors=buffer.accessors, bufferViews=buffer.views,
        buffers=[pygltflib.Buffer(byteLength=len(buffer.data))],
    )
    document.set_binary_blob(bytes(buffer.data))
    return document


def export_clip_gltf(
    path: str | Path,
    *,
    clip_id: str,
    skeleton: Skeleton,
    xyz: np.ndarray,
    bone_lengths: np.ndarray,
    fps: float,
    units: str,
    hand: str,
    keep_lengths: bool = False,
) -> Path:
    """Write a clip as a skinned glTF binary (``.glb``; see the module doc).

    Parameters
    ----------
    path
        Output ``.glb`` file; its folder must exist; an existing file is replaced
        atomically.
    clip_id, skeleton, xyz, bone_lengths, fps, units, hand, keep_lengths
        As for :func:`handdb.export.usd.export_clip_usd`.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ParameterError
        On another suffix than ``.glb``, an unknown unit or hand, a non-positive fps, or
        arrays whose shapes do not match ``skeleton``.
    StageError
        If the positions have NaN (fill gaps first).
    """
    path = Path(path)
    if path.suffix != GLB_SUFFIX:
        raise ParameterError(f"{path}: the suffix must be {GLB_SUFFIX}")
    xyz, bone_lengths = check_skinned_clip(skeleton, xyz, bone_lengths, fps=fps, units=units,
                                           hand=hand)
    require_filled(xyz, f"clip '{clip_id}'")
    motion = joint_rotations(xyz, skeleton, bone_lengths, keep_lengths=keep_lengths)
    document = build_clip_gltf(clip_id=clip_id, skeleton=skeleton, motion=motion,
                               bone_lengths=bone_lengths, fps=fps, units=units, hand=hand)
    with staged_file(path, ".gltf-export-") as written:
        document.save_binary(str(written))
    return path

