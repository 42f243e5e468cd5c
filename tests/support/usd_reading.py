"""Read exported USD back through UsdSkel, as a DCC tool would."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pxr import Usd, UsdGeom, UsdSkel, UsdValidation


@dataclass
class OpenedClip:
    """An exported clip reopened; the queries live only as long as ``cache``."""

    stage: Usd.Stage
    cache: UsdSkel.Cache
    skel_query: UsdSkel.SkeletonQuery
    skinning_query: UsdSkel.SkinningQuery


def open_skeleton(path) -> OpenedClip:
    """Reopen the clip at ``path`` and query its skeleton and mesh through UsdSkel."""
    stage = Usd.Stage.Open(str(path))
    root = UsdSkel.Root(stage.GetDefaultPrim())
    cache = UsdSkel.Cache()
    cache.Populate(root, Usd.TraverseInstanceProxies())
    skeleton = UsdSkel.Skeleton(stage.GetPrimAtPath(root.GetPath().AppendChild("Skeleton")))
    mesh = stage.GetPrimAtPath(root.GetPath().AppendChild("Mesh"))
    return OpenedClip(stage, cache, cache.GetSkelQuery(skeleton), cache.GetSkinningQuery(mesh))


def joint_world_positions(clip: OpenedClip, n_frames: int) -> np.ndarray:
    """Joint positions ``(T, J, 3)`` in stage axes from UsdSkel's own forward kinematics."""
    return np.stack([
        np.array(clip.skel_query.ComputeJointWorldTransforms(UsdGeom.XformCache(frame)))[:, 3, :3]
        for frame in range(n_frames)
    ])


def validation_errors(stage) -> list:
    """Every error of every validator registered with usd-core."""
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    errors = UsdValidation.ValidationContext(validators).Validate(stage)
    return [e for e in errors if e.GetType() == UsdValidation.ValidationErrorType.Error]
