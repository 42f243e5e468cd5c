"""Export a clip as a UsdSkel animation with a skinned hand mesh (usd-core, module ``pxr``).

Layout of the exported stage (``<Hand>`` is ``RightHand`` or ``LeftHand``)::

    /<Hand>            SkelRoot (default prim; customData handdb:clipId, handdb:hand)
    /<Hand>/Skeleton   Skeleton: joints, bindTransforms, restTransforms;
                       SkelBindingAPI with skel:animationSource -> Animation
    /<Hand>/<clip>     SkelAnimation named after the clip (:func:`animation_name`):
                       translations, rotations at every frame that places every
                       joint (a channel equal at every frame once, as its
                       default), scales once
    /<Hand>/Mesh       Mesh of capsules and palm, SkelBindingAPI bound to the Skeleton

Axes. handdb's 3D frame is the camera's: ``x`` right, ``y`` down, ``z`` away from the
camera. The stage is Y-up and right-handed, and is handdb's frame turned 180 degrees
about ``x`` (:data:`handdb.export.rotations.CAMERA_TO_Y_UP`): ``(x, y, z) -> (x, -y, -z)``, so
USD's ``+Y`` is up in the image and ``+Z`` points towards the camera: a USD camera on ``+Z``
looking down ``-Z`` sees what the source camera saw. The turn is applied to the root
joint only; every other joint's local transform is unchanged.

Lengths stay in the clip's units and ``metersPerUnit`` says which. Frame ``i`` is at time
code ``i``; ``timeCodesPerSecond`` and ``framesPerSecond`` are the clip's fps.

Frames without every joint. A detector's first or last frames often see no point, and
those stay without positions in the database. The animation has a time sample at each
frame that places every joint and none elsewhere, and the stage's start and end time codes
are the first and last such frame: Blender and Maya open it on the frames the clip shows,
each at its own frame number. USD holds the first sample before it and the last after it,
and interpolates between the samples either side of a frame inside the span that lacks a
joint (rotations slerped), so every DCC sees the same pose at every time.

Joint transforms come from :func:`handdb.export.rotations.joint_rotations` unless the caller
passes its own (e.g. fitted) :class:`~handdb.export.rotations.JointMotion`. By default the
animation reproduces the positions exactly: where they disagree with the bone lengths
(noisy lifting), a bone takes its measured length in that frame through the joint's
translation channel. ``keep_lengths=True`` imposes the bone lengths instead (rigid bones,
measured directions). The bind and rest pose is the average hand of
:func:`handdb.export.rotations.rest_pose` with the given bone lengths; the mesh is built in it.
"""

from __future__ import annotations

import re
import threading
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdSkel, UsdUtils, Vt
from scipy.spatial.transform import Rotation

from handdb.clip import METERS_PER_UNIT
from handdb.errors import ParameterError, StageError
from handdb.export.clip_checks import check_skinned_clip, placed_frames
from handdb.export.mesh import INFLUENCES, hand_mesh
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

#: USD loads its plugins when a process makes its first stage, and two threads doing that
#: at once can deadlock with the GIL held: 3 of 15 fresh processes hung whose two threads
#: each made a stage at the same moment, none of 15 once one stage had been made before
#: (usd-core 26.11). A build exports clips from several threads, so a process's first stage
#: is made under this lock.
_FIRST_STAGE = threading.Lock()
_first_stage_made = False

#: File suffixes written as a plain layer (``.usd`` is written as binary crate).
LAYER_SUFFIXES = (".usd", ".usdc", ".usda")
USDZ_SUFFIX = ".usdz"


def joint_paths(skeleton: Skeleton) -> list[str]:
    """UsdSkel joint paths (``wrist/index_mcp/index_pip``), parents before children."""
    paths: list[str] = []
    for joint, parent in zip(skeleton.joints, skeleton.parents, strict=True):
        paths.append(joint if parent < 0 else f"{paths[parent]}/{joint}")
    return paths


#: Children of the SkelRoot besides the animation, whose names it must not take.
_SKEL_ROOT_CHILDREN = ("Skeleton", "Mesh")


def animation_name(clip_id: str) -> str:
    """Name of the clip's ``SkelAnimation`` prim: the clip id as a valid USD identifier.

    Every character but ASCII letters, digits and ``_`` becomes ``_``, a leading digit (or
    an empty id) gets a ``_`` in front, and an id equal to another child of the SkelRoot
    (``Skeleton``, ``Mesh``) gets ``_Animation`` after it, so ``"rapid-s01"`` is
    ``rapid_s01`` and ``"01"`` is ``_01``. Blender names the imported action after it.
    """
    name = re.sub(r"[^A-Za-z0-9_]", "_", clip_id)
    if not name or name[0].isdigit():
        name = f"_{name}"
    return f"{name}_Animation" if name in _SKEL_ROOT_CHILDREN else name


def _new_stage() -> Usd.Stage:
    """An empty in-memory stage; the process's first one is made alone (:data:`_FIRST_STAGE`)."""
    global _first_stage_made
    if not _first_stage_made:
        with _FIRST_STAGE:
            stage = Usd.Stage.CreateInMemory()
            _first_stage_made = True
            return stage
    return Usd.Stage.CreateInMemory()


def _usd_matrices(orientations: np.ndarray, positions: np.ndarray) -> Vt.Matrix4dArray:
    """USD (row-vector) 4x4 matrices from rotation matrices ``(N, 3, 3)`` and positions."""
    matrices = np.zeros((len(orientations), 4, 4))
    matrices[:, :3, :3] = np.swapaxes(orientations, -1, -2)
    matrices[:, 3, :3] = positions
    matrices[:, 3, 3] = 1.0
    return Vt.Matrix4dArray.FromNumpy(matrices)


def _set_stage_metadata(stage: Usd.Stage, frames: np.ndarray, fps: float, units: str) -> None:
    """Axes, units, rate and the time span ``frames[0]..frames[-1]`` of the stage."""
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, METERS_PER_UNIT[units])
    stage.SetTimeCodesPerSecond(fps)
    stage.SetFramesPerSecond(fps)
    stage.SetStartTimeCode(float(frames[0]))
    stage.SetEndTimeCode(float(frames[-1]))


def _is_constant(values: np.ndarray) -> bool:
    """Whether every frame of ``values`` ``(T, ...) float32`` equals the first.

    Equal to float32 precision: within one epsilon of the channel's largest magnitude, so
    round-off in a rigid bone's offset (``1e-14`` where it should be zero) does not count.
    """
    tolerance = np.finfo(np.float32).eps * float(np.abs(values).max())
    return bool(np.abs(values - values[0]).max() <= tolerance)


def _author_animation(anim: UsdSkel.Animation, motion: JointMotion, frames: np.ndarray) -> None:
    """Author every channel of ``anim``: a time sample per frame, or once if constant.

    ``frames`` ``(T,) int64`` is the time code of each of ``motion``'s frames.

    A channel equal at every frame (``scales`` always; ``translations`` of a rigid hand
    that keeps its bone lengths and does not move; any channel of a one-frame clip) is
    written once as the attribute's default, which UsdSkel holds at every time. The others
    get a sample at every frame: a channel with neither would fall back to the rest pose.
    The values go straight into the layer's specs inside one change block, so the stage
    recomposes once, not once per sample.
    """
    n_joints = motion.rotations.shape[1]
    xyzw = np.ascontiguousarray(np.roll(motion.rotations, -1, axis=-1), dtype=np.float32)
    translations = np.ascontiguousarray(motion.translations, dtype=np.float32)
    anim.CreateScalesAttr(Vt.Vec3hArray.FromNumpy(np.ones((n_joints, 3), dtype=np.float16)))
    layer = anim.GetPrim().GetStage().GetEditTarget().GetLayer()
    channels = [(anim.CreateRotationsAttr(), Vt.QuatfArray.FromNumpy, xyzw),
                (anim.CreateTranslationsAttr(), Vt.Vec3fArray.FromNumpy, translations)]
    with Sdf.ChangeBlock():
        # Only Sdf calls in here: Usd's API is not safe inside a change block.
        for attribute, to_vt, values in channels:
            path = attribute.GetPath()
            if _is_constant(values):
                layer.GetAttributeAtPath(path).default = to_vt(values[0])
                continue
            for frame, value in zip(frames.tolist(), map(to_vt, values), strict=True):
                layer.SetTimeSample(path, frame, value)


def _author_mesh(
    stage: Usd.Stage, path: Sdf.Path, skeleton: Skeleton, bone_lengths: np.ndarray,
    skel: UsdSkel.Skeleton,
) -> None:
    hand = hand_mesh(skeleton, bone_lengths)
    mesh = UsdGeom.Mesh.Define(stage, path)
    points = np.ascontiguousarray(hand.vertices, dtype=np.float32)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(hand.faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(hand.faces.astype(np.int32).ravel()))
    mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([points.min(0), points.max(0)])))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    binding.CreateJointIndicesPrimvar(False, INFLUENCES).Set(
        Vt.IntArray.FromNumpy(hand.joint_indices.astype(np.int32).ravel()))
    binding.CreateJointWeightsPrimvar(False, INFLUENCES).Set(
        Vt.FloatArray.FromNumpy(hand.joint_weights.astype(np.float32).ravel()))
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1.0))


def build_clip_stage(
    *,
    clip_id: str,
    skeleton: Skeleton,
    motion: JointMotion,
    bone_lengths: np.ndarray,
    fps: float,
    units: str,
    hand: str,
    frames: np.ndarray | None = None,
) -> Usd.Stage:
    """Build the in-memory stage of a clip (see the module doc for its layout).

    Parameters
    ----------
    clip_id
        The clip's id, recorded as the SkelRoot's ``handdb:clipId`` custom data; the
        SkelAnimation is named after it (:func:`animation_name`).
    skeleton
        Skeleton of the motion.
    motion
        Local joint transforms in handdb's camera frame, ``T`` frames, clip units.
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.
    fps
        Frames per second.
    units
        Clip length unit: ``mm``, ``cm``, ``m`` or ``in``.
    hand
        ``left`` or ``right``.
    frames
        ``(T,) int64`` increasing frame number (time code) of each of ``motion``'s frames;
        ``None`` for ``0 .. T - 1``.

    Returns
    -------
    pxr.Usd.Stage
    """
    frames = np.arange(motion.n_frames) if frames is None else np.asarray(frames, np.int64)
    if frames.shape != (motion.n_frames,) or (np.diff(frames) <= 0).any():
        raise ParameterError(f"frames must be {motion.n_frames} increasing frame numbers, one "
                             f"per frame of the motion; got shape {frames.shape}")
    stage = _new_stage()
    _set_stage_metadata(stage, frames, fps, units)
    root = UsdSkel.Root.Define(stage, Sdf.Path(f"/{hand.capitalize()}Hand"))
    stage.SetDefaultPrim(root.GetPrim())
    root.GetPrim().SetCustomDataByKey("handdb:clipId", clip_id)
    root.GetPrim().SetCustomDataByKey("handdb:hand", hand)

    joints = Vt.TokenArray(joint_paths(skeleton))
    rest = rest_pose(skeleton, bone_lengths)
    rest_local = Rotation.from_quat(rest.rotations[0], scalar_first=True).as_matrix()
    bind_orientations, bind_positions = world_transforms(rest, skeleton)
    skel = UsdSkel.Skeleton.Define(stage, root.GetPath().AppendChild("Skeleton"))
    skel.CreateJointsAttr(joints)
    skel.CreateJointNamesAttr(Vt.TokenArray(list(skeleton.joints)))
    skel.CreateBindTransformsAttr(_usd_matrices(bind_orientations[0], bind_positions[0]))
    skel.CreateRestTransformsAttr(_usd_matrices(rest_local, rest.translations[0]))

    anim = UsdSkel.Animation.Define(stage, root.GetPath().AppendChild(animation_name(clip_id)))
    anim.CreateJointsAttr(joints)
    _author_animation(anim, turn_root(motion, skeleton, CAMERA_TO_Y_UP), frames)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets(
        [anim.GetPath()])

    _author_mesh(stage, root.GetPath().AppendChild("Mesh"), skeleton, bone_lengths, skel)
    return stage


def _write_atomically(stage: Usd.Stage, path: Path) -> None:
    """Write ``stage`` to ``path`` (format from its suffix) via a file renamed into place."""
    with staged_file(path, ".usd-export-") as written:
        if path.suffix == USDZ_SUFFIX:
            layer_file = written.with_suffix(".usdc")
            stage.GetRootLayer().Export(str(layer_file))
            if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(layer_file)), str(written)):
                raise StageError(f"usd-core could not package {path}")
        elif not stage.GetRootLayer().Export(str(written)):
            raise StageError(f"usd-core could not write {path}")


def export_clip_usd(
    path: str | Path,
    *,
    clip_id: str,
    skeleton: Skeleton,
    xyz: np.ndarray,
    bone_lengths: np.ndarray,
    fps: float,
    units: str,
    hand: str,
    rotations: JointMotion | None = None,
    keep_lengths: bool = False,
) -> Path:
    """Write a clip as a UsdSkel animation with a skinned hand mesh.

    Parameters
    ----------
    path
        Output file: ``.usd`` or ``.usdc`` (binary crate), ``.usda`` (text) or ``.usdz``
        (package). Its folder must exist; an existing file is replaced atomically.
    clip_id
        The clip's id.
    skeleton
        Skeleton of ``xyz``.
    xyz
        Joint positions, ``(T, J, 3) float64``, clip units, handdb's camera frame; NaN where
        a joint has no position. Only the frames that place every joint are animated (see
        the module doc).
    bone_lengths
        ``(J,) float64`` length of the bone ending at each joint, clip units.
    fps
        Frames per second, > 0.
    units
        ``mm``, ``cm``, ``m`` or ``in``.
    hand
        ``left`` or ``right``.
    rotations
        Local joint transforms of all ``T`` frames, to export instead of those computed
        from ``xyz``.
    keep_lengths
        When computing the transforms: ``False`` reproduces ``xyz`` exactly, ``True``
        gives every bone its length from ``bone_lengths`` (see the module doc).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ParameterError
        On an unknown suffix, unit or hand, a non-positive fps, or arrays whose shapes do
        not match ``skeleton``.
    StageError
        If no frame places every joint, or usd-core cannot write the file.
    """
    path = Path(path)
    if path.suffix not in (*LAYER_SUFFIXES, USDZ_SUFFIX):
        raise ParameterError(f"{path}: the suffix must be one of {(*LAYER_SUFFIXES, USDZ_SUFFIX)}")
    xyz, bone_lengths = check_skinned_clip(skeleton, xyz, bone_lengths, fps=fps, units=units,
                                           hand=hand)
    frames = None
    if rotations is None:
        frames = placed_frames(xyz, f"clip '{clip_id}'")
        placed = xyz if len(frames) == len(xyz) else xyz[frames]
        rotations = joint_rotations(placed, skeleton, bone_lengths, keep_lengths=keep_lengths)
    stage = build_clip_stage(clip_id=clip_id, skeleton=skeleton, motion=rotations,
                             bone_lengths=bone_lengths, fps=fps, units=units, hand=hand,
                             frames=frames)
    _write_atomically(stage, path)
    return path
