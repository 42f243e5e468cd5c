"""Hand skeleton topologies, read from ``schemas/skeletons/*.json``.

A skeleton is a tree of named joints. Each joint has a parent (``None`` for the root), a
finger (``thumb``, ``index``, ``middle``, ``ring``, ``little`` or ``palm``) and a role
(``wrist``, ``cmc``, ``mcp``, ``pip``, ``dip``, ``ip``, ``tip``, ``palm_fold``,
``palm_center``). A *bone* is named by its child joint: the bone ``index_pip`` runs from
``index_mcp`` to ``index_pip``. Joint names are the canonical names of handdb
(the ``mediapipe21`` names), so joints of different presets correspond by name.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np

from handdb.errors import BoneLengthError, SkeletonError
from handdb.paths import SCHEMAS_DIR
from handdb.vectors import norm

SKELETONS_DIR = SCHEMAS_DIR / "skeletons"

#: Fingers from the thumb side to the little-finger side.
FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little")


@dataclass(frozen=True)
class Skeleton:
    """A hand skeleton: joints in topological order (every parent before its children).

    Attributes
    ----------
    name
        Preset name, e.g. ``"mediapipe21"``.
    joints
        Canonical joint names, ``(J,)``.
    parents
        Index of each joint's parent, ``(J,) int64``, read-only; ``-1`` for the root.
    fingers
        Finger of each joint, ``(J,)``.
    roles
        Anatomical role of each joint, ``(J,)``.
    ids
        The source's own numeric id of each joint (``thesis21``: the thesis's feature
        point numbers), ``(J,)``.
    source_names
        The source's own name of each joint, ``(J,)``.
    reference_lengths
        Bone lengths shipped with the preset (child joint -> length), may be empty.
    reference_units
        Units of ``reference_lengths``.
    """

    name: str
    joints: tuple[str, ...]
    parents: np.ndarray
    fingers: tuple[str, ...]
    roles: tuple[str, ...]
    ids: tuple[int, ...]
    source_names: tuple[str, ...]
    description: str = ""
    reference_lengths: dict[str, float] = field(default_factory=dict)
    reference_units: str | None = None

    @property
    def n_joints(self) -> int:
        """Number of joints ``J``."""
        return len(self.joints)

    @property
    def root(self) -> int:
        """Index of the root joint."""
        return int(np.flatnonzero(self.parents < 0)[0])

    def index(self, joint: str) -> int:
        """Return the index of ``joint``; raise :class:`SkeletonError` if it is not here."""
        try:
            return self.joints.index(joint)
        except ValueError:
            raise SkeletonError(
                f"joint '{joint}' is not in skeleton '{self.name}' "
                f"(its joints: {', '.join(self.joints)})"
            ) from None

    def indices(self, joints: list[str] | tuple[str, ...]) -> np.ndarray:
        """Return the indices of several joints, ``(K,) int64``."""
        return np.array([self.index(j) for j in joints], dtype=np.int64)

    @property
    def bones(self) -> np.ndarray:
        """Bones as ``(B, 2) int64`` rows ``(parent, child)``, in topological order."""
        child = np.flatnonzero(self.parents >= 0)
        return np.stack([self.parents[child], child], axis=1)

    @property
    def bone_names(self) -> tuple[str, ...]:
        """Bone names (the child joint of each bone), ``(B,)``."""
        return tuple(self.joints[c] for c in self.bones[:, 1])

    def children(self, joint: int) -> np.ndarray:
        """Indices of the children of joint index ``joint``."""
        return np.flatnonzero(self.parents == joint)

    def finger_chain(self, finger: str) -> np.ndarray:
        """Joint indices of ``finger`` from its base to its tip, ``(K,) int64``."""
        return np.array([i for i, f in enumerate(self.fingers) if f == finger], dtype=np.int64)

    def depth(self) -> np.ndarray:
        """Number of bones between each joint and the root, ``(J,) int64``."""
        depth = np.zeros(self.n_joints, dtype=np.int64)
        for j in range(self.n_joints):
            if self.parents[j] >= 0:
                depth[j] = depth[self.parents[j]] + 1
        return depth

    def role_of(self, joint: str) -> str:
        """Anatomical role of ``joint``."""
        return self.roles[self.index(joint)]


def _parse(doc: dict, source: Path) -> Skeleton:
    try:
        joints = doc["joints"]
        names = [j["name"] for j in joints]
        parent_names = [j["parent"] for j in joints]
        fingers = [j["finger"] for j in joints]
        roles = [j["role"] for j in joints]
    except (KeyError, TypeError) as exc:
        raise SkeletonError(
            f"{source}: every joint needs name, parent, finger, role ({exc})") from None
    if len(set(names)) != len(names):
        raise SkeletonError(f"{source}: joint names must be unique")
    parents = np.full(len(names), -1, dtype=np.int64)
    for i, p in enumerate(parent_names):
        if p is None:
            continue
        if p not in names[:i]:
            raise SkeletonError(
                f"{source}: joint '{names[i]}' lists parent '{p}', which must be a joint "
                "listed before it"
            )
        parents[i] = names.index(p)
    if int((parents < 0).sum()) != 1:
        raise SkeletonError(f"{source}: a skeleton has exactly one root (parent null)")
    for f in fingers:
        if f not in (*FINGERS, "palm"):
            raise SkeletonError(f"{source}: unknown finger '{f}'")
    ref = doc.get("reference_lengths") or {}
    parents.flags.writeable = False  # presets are cached and shared: nobody may edit them
    return Skeleton(
        name=doc["name"],
        joints=tuple(names),
        parents=parents,
        fingers=tuple(fingers),
        roles=tuple(roles),
        ids=tuple(int(j.get("id", i)) for i, j in enumerate(joints)),
        source_names=tuple(str(j.get("source_name", j["name"])) for j in joints),
        description=doc.get("description", ""),
        reference_lengths={k: float(v) for k, v in ref.get("bones", {}).items()},
        reference_units=ref.get("units"),
    )


def available_skeletons() -> tuple[str, ...]:
    """Names of the presets in ``schemas/skeletons``."""
    return tuple(sorted(p.stem for p in SKELETONS_DIR.glob("*.json")))


@cache
def load_skeleton(name: str) -> Skeleton:
    """Load the preset ``name`` from ``schemas/skeletons/<name>.json``.

    Raises
    ------
    SkeletonError
        If there is no such preset or its file is inconsistent.
    """
    path = SKELETONS_DIR / f"{name}.json"
    if not isinstance(name, str) or "/" in name or not path.is_file():
        raise SkeletonError(
            f"unknown skeleton '{name}'; known presets: {', '.join(available_skeletons())}"
        )
    with path.open() as fh:
        return _parse(json.load(fh), path)


def frame_bone_lengths(positions: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Length of every bone in every frame.

    Parameters
    ----------
    positions
        ``(T, J, D) float64`` joint positions (``D`` = 3, or 2 for image points), any
        unit; NaN where missing.
    skeleton
        The skeleton of the joint axis.

    Returns
    -------
    np.ndarray
        ``(T, J) float64``: length of the bone ending at each joint, in the unit of
        ``positions``; NaN for the root and where either end is missing.
    """
    lengths = np.full(positions.shape[:2], np.nan)
    parent, child = skeleton.bones.T
    lengths[:, child] = norm(positions[:, child] - positions[:, parent])
    return lengths


def bone_length_array(skeleton: Skeleton, lengths: dict[str, float], *,
                      complete: bool = False) -> np.ndarray:
    """Bone lengths as ``(J,) float64``, the length of the bone ending at each joint.

    Parameters
    ----------
    skeleton
        Orders the result.
    lengths
        ``{child joint: length}`` (a sidecar's ``bone_lengths``), any one unit.
    complete
        Require a positive, finite length for every bone of ``skeleton``.

    Returns
    -------
    numpy.ndarray
        NaN at the root (no bone ends there) and for bones ``lengths`` lacks.

    Raises
    ------
    SkeletonError
        If ``lengths`` names a joint that is not a bone of ``skeleton``.
    BoneLengthError
        With ``complete``, naming the first bone without a valid length.
    """
    out = np.full(skeleton.n_joints, np.nan)
    for name, length in lengths.items():
        joint = skeleton.index(name)
        if joint == skeleton.root:
            raise SkeletonError(f"'{name}' is the root of skeleton '{skeleton.name}': no bone "
                                "ends there")
        out[joint] = length
    if complete:
        for bone in skeleton.bone_names:
            length = out[skeleton.index(bone)]
            if not np.isfinite(length) or length <= 0:
                raise BoneLengthError(
                    f"skeleton '{skeleton.name}': bone '{bone}' needs a positive length, "
                    f"got {lengths.get(bone)!r}")
    return out
def correspondence(source: Skeleton, target: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Return index pairs of the joints the two skeletons share.

    Returns
    -------
    src, dst
        ``(K,) int64`` each: joint ``source.joints[src[k]]`` is ``target.joints[dst[k]]``.
    """
    shared = [(i, target.joints.index(name)) for i, name in enumerate(source.joints)
              if name in target.joints]
    if not shared:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    src, dst = np.array(shared, dtype=np.int64).T
    return src, dst


def convert_points(points: np.ndarray, source: Skeleton, target: Skeleton) -> np.ndarray:
    """Map per-joint values from ``source`` to ``target`` order.

    Parameters
    ----------
    points
        ``(..., J_source, D)`` values (coordinates, or ``D = 1`` for scalars).
    source, target
        The skeletons the joint axis is ordered by.

    Returns
    -------
    numpy.ndarray
        ``(..., J_target, D) float64``; NaN for target joints the source lacks.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.shape[-2] != source.n_joints:
        raise ValueError(
            f"points have {points.shape[-2]} joints on axis -2, skeleton '{source.name}' "
            f"has {source.n_joints}"
        )
    out = np.full(points.shape[:-2] + (target.n_joints, points.shape[-1]), np.nan)
    src, dst = correspondence(source, target)
    out[..., dst, :] = points[..., src, :]
    return out
