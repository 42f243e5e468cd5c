"""Long-form points as a reader returns them, validated on construction.

A reader turns a file into :class:`Observations` (2D points) or :class:`Positions` (3D
ground truth): one row per (frame, joint) the source reports, each row remembering the
file and 1-based line it came from so that any later complaint can point at it. Both
classes check their rows when built and raise :class:`~handdb.errors.InputError` at the
first bad row, so a reader never hands on half-valid data.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from handdb.clip import ClipSpec
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton


def joint_lookup(spec: ClipSpec, skeleton: Skeleton) -> dict[str, int]:
    """Map every name a source may use for a joint to the joint's index.

    A source names a joint by its canonical name or by a tool name the sidecar's
    ``joint_map`` maps to a canonical name.
    """
    lookup = {name: i for i, name in enumerate(skeleton.joints)}
    lookup.update({tool: skeleton.index(canonical) for tool, canonical in spec.joint_map.items()})
    return lookup


def unknown_joint(file: str, name: str, spec: ClipSpec, skeleton: Skeleton, *,
                  line: int | None = None, field: str = "joint") -> InputError:
    """Return the error for a joint name that is neither canonical nor in the ``joint_map``."""
    mapped = (f"; the sidecar's joint_map maps {', '.join(sorted(spec.joint_map))}"
              if spec.joint_map else "")
    return InputError(
        file,
        f"unknown joint '{name}': skeleton '{skeleton.name}' knows "
        f"{', '.join(skeleton.joints)}{mapped}. Rename it, or map it to one of these in "
        "the sidecar's joint_map",
        line=line, field=field, clip_id=spec.clip_id,
    )


def resolve_joints(names: Sequence[str], spec: ClipSpec, skeleton: Skeleton) -> np.ndarray:
    """Joint index of each name, ``(K,) int64``; ``-1`` for names nothing maps."""
    lookup = joint_lookup(spec, skeleton)
    return np.array([lookup.get(name, -1) for name in names], dtype=np.int64)


@dataclass(frozen=True, kw_only=True)
class _Rows:
    """Row bookkeeping shared by :class:`Observations` and :class:`Positions`."""

    frame: np.ndarray
    joint: np.ndarray
    line: np.ndarray
    source: np.ndarray
    files: tuple[str, ...]
    skeleton: Skeleton
    n_frames: int
    fields: Mapping[str, str] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()

    @property
    def n_rows(self) -> int:
        """Number of rows ``N``."""
        return int(self.frame.shape[0])

    def field_name(self, generic: str, row: int) -> str:
        """Return the source's name of column ``generic`` at ``row`` (e.g. ``index_tip.x``)."""
        template = self.fields.get(generic, generic)
        names = self.joint_names or self.skeleton.joints
        return template.format(joint=names[self.joint[row]])

    def error(self, row: int, generic_field: str, reason: str) -> InputError:
        """Return an :class:`InputError` located at ``row`` and column ``generic_field``."""
        line = int(self.line[row])
        return InputError(self.files[self.source[row]], reason, line=line or None,
                          field=self.field_name(generic_field, row))

    def where(self, row: int) -> str:
        """``file:line`` (or just the file) of ``row``, for messages naming two rows."""
        line = int(self.line[row])
        file = self.files[self.source[row]]
        return f"{file}:{line}" if line else file

    def _check_rows(self) -> None:
        n = self.n_rows
        for name in ("frame", "joint", "line", "source"):
            array = getattr(self, name)
            if array.shape != (n,) or array.dtype.kind != "i":
                raise ValueError(f"{name} must be an integer array of shape ({n},)")
        if n and (self.joint.min() < 0 or self.joint.max() >= self.skeleton.n_joints):
            raise ValueError("joint indices must index the skeleton")
        negative = np.flatnonzero(self.frame < 0)
        if negative.size:
            row = negative[0]
            raise self.error(row, "frame", f"frame {self.frame[row]} is negative; "
                             "frames count from 0")
        if n and self.n_frames <= self.frame.max():
            raise ValueError("n_frames must exceed every frame number")
        key = self.frame * self.skeleton.n_joints + self.joint
        order = np.argsort(key, kind="stable")
        repeated = np.flatnonzero(key[order][1:] == key[order][:-1])
        if repeated.size:
            first = order[repeated]
            second = order[repeated + 1]
            pick = np.argmin(np.maximum(first, second))
            row, again = int(first[pick]), int(second[pick])
            raise self.error(
                again, "frame",
                f"frame {self.frame[row]} joint '{self.skeleton.joints[self.joint[row]]}' "
                f"is given twice, here and at {self.where(row)}; keep one of them")

    def _check_not_infinite(self, values: dict[str, np.ndarray]) -> None:
        arrays = np.stack(list(values.values()), axis=1)
        infinite = np.argwhere(np.isinf(arrays))
        if infinite.size:
            row, col = infinite[0]
            raise self.error(row, list(values)[col],
                             f"{arrays[row, col]} is not a finite number")


@dataclass(frozen=True, kw_only=True)
class Observations(_Rows):
    """2D points of one clip in long form, one row per reported (frame, joint).

    Attributes
    ----------
    frame
        ``(N,) int64``, frame number from 0.
    joint
        ``(N,) int64``, index into ``skeleton.joints``.
    u, v
        ``(N,) float64``, pixels (x right, y down); both NaN where the source marks the
        point missing.
    confidence
        ``(N,) float64`` in [0, 1]; NaN where the source gives none.
    line
        ``(N,) int64``, 1-based line of the row in its file; 0 for formats without lines.
    source
        ``(N,) int64``, index into ``files`` of the file the row came from.
    files
        The files the rows came from.
    skeleton
        The skeleton ``joint`` indexes.
    n_frames
        Number of frames the source spans (frames without points included).
    fields
        The source's names of the generic columns (``frame``, ``joint``, ``u``, ``v``,
        ``confidence``) where they differ; ``{joint}`` in a name stands for the joint.
    joint_names
        The source's name of each skeleton joint, for ``{joint}`` in ``fields``; empty
        for the canonical names.
    """

    u: np.ndarray
    v: np.ndarray
    confidence: np.ndarray

    def __post_init__(self) -> None:
        self._check_rows()
        for name in ("u", "v", "confidence"):
            if getattr(self, name).shape != (self.n_rows,):
                raise ValueError(f"{name} must have shape ({self.n_rows},)")
        self._check_not_infinite({"u": self.u, "v": self.v})
        half = np.flatnonzero(np.isnan(self.u) != np.isnan(self.v))
        if half.size:
            row = half[0]
            missing = "u" if np.isnan(self.u[row]) else "v"
            raise self.error(row, missing, "is empty but its partner coordinate is not; give "
                             "both coordinates, or leave both empty for a missing point")
        outside = np.flatnonzero(~np.isnan(self.confidence)
                                 & ((self.confidence < 0) | (self.confidence > 1)))
        if outside.size:
            row = outside[0]
            raise self.error(row, "confidence",
                             f"confidence {self.confidence[row]} lies outside [0, 1]")

    @property
    def uv(self) -> np.ndarray:
        """``(N, 2) float64`` pixels."""
        return np.stack([self.u, self.v], axis=1)


@dataclass(frozen=True, kw_only=True)
class Positions(_Rows):
    """3D ground-truth points of one clip in long form, one row per (frame, joint).

    Attributes are those of :class:`Observations` without ``u, v, confidence`` and with
    ``xyz``: ``(N, 3) float64`` in the clip's units, camera frame (x right, y down,
    z away from the camera), every value finite.
    """

    xyz: np.ndarray

    def __post_init__(self) -> None:
        self._check_rows()
        if self.xyz.shape != (self.n_rows, 3):
            raise ValueError(f"xyz must have shape ({self.n_rows}, 3)")
        self._check_not_infinite(dict(zip("xyz", self.xyz.T, strict=True)))
        missing = np.argwhere(np.isnan(self.xyz))
        if missing.size:
            row, axis = missing[0]
            raise self.error(row, "xyz"[axis], "is empty; ground truth rows need x, y and z "
                             "(leave out the row of a joint without ground truth)")


def single_file_rows(path: str | Path, n: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """``source`` and ``files`` for rows that all come from the one file ``path``."""
    return np.zeros(n, dtype=np.int64), (str(path),)
