"""The signature of a lifting method, and :func:`lift`, the one entry point."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Protocol

import numpy as np

from handdb.checks import check_hand
from handdb.clip import SAMPLINGS, VIDEO, Camera, finite_points
from handdb.errors import BoneLengthError
from handdb.hand.skeletons import Skeleton
from handdb.lifting.methods import DEFAULT_METHOD, METHODS
from handdb.lifting.result import LiftResult


class LiftMethod(Protocol):
    """Signature every lifting method implements (see :func:`lift`)."""

    def __call__(self, uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                 camera: Camera, *, hand: str) -> LiftResult:
        """Lift ``uv`` to 3D; see :func:`lift` (a method may take parameters of its own)."""


def _check_inputs(uv: np.ndarray, skeleton: Skeleton, bone_lengths: np.ndarray,
                  hand: str) -> None:
    n_joints = skeleton.n_joints
    if uv.ndim != 3 or uv.shape[1:] != (n_joints, 2):
        raise ValueError(f"uv must be (T, {n_joints}, 2) for skeleton '{skeleton.name}', "
                         f"got {uv.shape}")
    if bone_lengths.shape != (n_joints,):
        raise ValueError(f"bone_lengths must be ({n_joints},), got {bone_lengths.shape}")
    bones = skeleton.bones[:, 1]
    bad = [skeleton.joints[j] for j in bones
           if not (np.isfinite(bone_lengths[j]) and bone_lengths[j] > 0)]
    if bad:
        raise BoneLengthError(f"bone lengths must be positive and finite; missing or invalid "
                              f"for {', '.join(bad)} (skeleton '{skeleton.name}')")
    check_hand(hand)


def lift(
    uv: np.ndarray,
    skeleton: Skeleton,
    bone_lengths: np.ndarray,
    camera: Camera,
    *,
    method: str = DEFAULT_METHOD,
    hand: str = "right",
    sampling: str = VIDEO,
    **params: Any,
) -> LiftResult:
    """Give every joint of every frame its depth.

    Parameters
    ----------
    uv
        ``(T, J, 2) float64``, pixels (x right, y down); NaN where a point is missing.
    skeleton
        The clip's skeleton; ``uv``'s joint axis follows its order.
    bone_lengths
        ``(J,) float64``, clip units: length of the bone ending at each joint, NaN for the
        root (see :func:`~handdb.hand.skeletons.bone_length_array`).
    camera
        ``orthographic`` (scale unknown) or ``pinhole`` (intrinsics in pixels).
    method
        A name from :func:`~handdb.lifting.methods.available_methods`.
    hand
        ``"right"`` or ``"left"``: which hand the clip shows.
    sampling
        :data:`~handdb.clip.VIDEO` (frames in time order: signs and scale are tied across
        frames) or :data:`~handdb.clip.IMAGES` (independent images: each frame is lifted
        on its own).
    **params
        Parameters of the method.

    Returns
    -------
    LiftResult
        Positions in clip units, camera frame, with per-bone sign confidence and length
        inconsistency.

    Raises
    ------
    UnknownNameError
        On an unknown method.
    ValueError
        On arrays of the wrong shape, or an unknown ``sampling``.
    BoneLengthError
        If a bone of the skeleton has no positive, finite length.
    """
    run = METHODS[method]
    uv = np.asarray(uv, dtype=np.float64)
    bone_lengths = np.asarray(bone_lengths, dtype=np.float64)
    _check_inputs(uv, skeleton, bone_lengths, hand)
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}, got {sampling!r}")
    if sampling == VIDEO or len(uv) < 2:
        lifted = run(uv, skeleton, bone_lengths, camera, hand=hand, **params)
    else:
        lifted = _joined([run(uv[t:t + 1], skeleton, bone_lengths, camera, hand=hand,
                              **params) for t in range(len(uv))])
    return _unseen_unplaced(lifted, uv)


def _unseen_unplaced(lifted: LiftResult, uv: np.ndarray) -> LiftResult:
    """``lifted`` with every coordinate NaN where the joint has no image point.

    A method may leave a coordinate it knows by convention on a joint it did not see (the
    orthographic root's ``z = 0``, a pinhole root depth interpolated over an empty frame);
    a stored position is either whole or absent.
    """
    unseen = ~finite_points(uv)
    if not unseen.any():
        return lifted
    xyz = lifted.xyz.copy()
    xyz[unseen] = np.nan
    return replace(lifted, xyz=xyz)


def _joined(frames: list[LiftResult]) -> LiftResult:
    """One result from the results of frames lifted one by one, in order."""
    notes = list(dict.fromkeys(r.note for r in frames if r.note))
    ambiguous = [t for t, r in enumerate(frames) if r.mirror_ambiguous]
    odds = [r.mirror_log_odds for r in frames if r.mirror_log_odds is not None]
    if ambiguous:
        notes.append(f"lifted image by image: the mirror is ambiguous in {len(ambiguous)} "
                     f"of {len(frames)} images (from image {ambiguous[0]})")
    return LiftResult(
        xyz=np.concatenate([r.xyz for r in frames]),
        sign_confidence=np.concatenate([r.sign_confidence for r in frames]),
        length_inconsistency=np.concatenate([r.length_inconsistency for r in frames]),
        scale=np.concatenate([r.scale for r in frames]),
        method=frames[0].method,
        mirror_ambiguous=bool(ambiguous),
        mirror_log_odds=min(odds) if odds else None,
        note="; ".join(notes),
    )
