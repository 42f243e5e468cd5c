"""Long-form points as a reader returns them, validated on construction.

A reader turns a file into :class:`Observations` (2D points) or :class:`Positions` (3D
ground truth): one row per (frame, joint) the source reports, each row remembering the
file and 1-based line it came from so that any later complaint can point at it. Both
classes check their rows when built and raise :class:`~handdb.errors.InputError` at the
first bad row, so a reader never hands on half-valid data.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from handdb.clip import VIDEO, ClipSpec, finite_points
from handdb.errors import InputError
from handdb.hand.skeletons import Skeleton
from handdb.ingest.limits import (
    MAX_FRAMES,
    NORMALISED_BOUND,
    frame_limit_reason,
    is_sparse,
    is_stray_run,
    longest_empty_run,
    quoted,
)
from handdb.ingest.sidecar import IGNORE_OTHERS

#: A function giving the 1-based line (or ``None``) and the field where a file's ``k``-th
#: name is written, for messages about that name.
Locate = Callable[[int], tuple[int | None, str]]


def _map_text(spec: ClipSpec) -> str:
    entries = [f"{k} to {'null' if v is None else v}" for k, v in spec.joint_map.items()]
    shown = ", ".join(entries[:8]) + (", ..." if len(entries) > 8 else "")
    return f"; the sidecar's joint_map maps {shown}" if entries else ""


def unknown_joint(file: str | Path, name: str, spec: ClipSpec, skeleton: Skeleton, *,
                  line: int | None = None, field: str = "joint") -> InputError:
    """Return the error for a name that is neither canonical nor a ``joint_map`` key."""
    return InputError(
        file,
        f"unknown joint {quoted(name)}: skeleton '{skeleton.name}' knows "
        f"{', '.join(skeleton.joints)}{_map_text(spec)}. Rename it, or map it in the "
        f"sidecar's joint_map to one of these, to null to ignore it, or add "
        f'"{IGNORE_OTHERS}": null to ignore every unmapped name',
        line=line, field=field, clip_id=spec.clip_id,
    )


def resolve_names(names: Sequence[str], spec: ClipSpec, skeleton: Skeleton,
                  file: str | Path, locate: Locate, *, fixed: bool = False) -> np.ndarray:
    """Joint index of each distinct name of a file, by the one ``joint_map`` rule.

    A name that is a key of the sidecar's ``joint_map`` is its value: a joint, or ignored
    (``null``). Any other canonical name is that joint. Any other name is ignored when
    the map has ``"*": null``, and refused otherwise. Formats with a fixed joint order
    (``fixed``: OpenPose, MediaPipe, ...) name joints canonically; those the skeleton
    lacks are dropped rather than refused.

    Parameters
    ----------
    names
        The file's distinct names, ``K`` of them.
    spec, skeleton
        The sidecar and its skeleton.
    file
        The file, for messages.
    locate
        ``locate(k)``: line and field where ``names[k]`` is written.
    fixed
        Whether the names are a fixed-order format's canonical names.

    Returns
    -------
    numpy.ndarray
        ``(K,) int64`` joint indices, ``-1`` for ignored names.

    Raises
    ------
    InputError
        For an unknown name, two names mapped to one joint, or a file whose every name
        is ignored.
    """
    joint_map = spec.joint_map
    ignore_others = IGNORE_OTHERS in joint_map or fixed
    indices = np.full(len(names), -1, dtype=np.int64)
    taken: dict[int, int] = {}
    for k, name in enumerate(names):
        canonical = joint_map.get(name, name if name in skeleton.joints else None)
        if canonical is None:
            if name not in joint_map and not ignore_others:
                line, field = locate(k)
                raise unknown_joint(file, name, spec, skeleton, line=line, field=field)
            continue
        joint = skeleton.index(canonical)
        if joint in taken:
            line, field = locate(k)
            raise InputError(file, f"{quoted(names[taken[joint]])} and {quoted(name)} both "
                             f"map to joint '{canonical}'; map one of them to null, or to "
                             "another joint", line=line, field=field, clip_id=spec.clip_id)
        taken[joint] = k
        indices[k] = joint
    if names and not taken:
        line, field = locate(0)
        shown = ", ".join(quoted(n) for n in names[:8]) + (", ..." if len(names) > 8 else "")
        raise InputError(file, f"none of its names ({shown}) is a joint of skeleton "
                         f"'{skeleton.name}' once the sidecar's joint_map is applied; "
                         + _joint_map_advice(names, skeleton),
                         line=line, field=field, clip_id=spec.clip_id)
    return indices


def _joint_map_advice(names: Sequence[str], skeleton: Skeleton) -> str:
    """How to map a file's names that are none of ``skeleton``'s joints.

    Names that are a joint once a tool's prefix (``Subject:`` of Vicon) is cut and case is
    ignored are offered as the example entries of the ``joint_map``.
    """
    matches = {name: bare for name in names
               if (bare := name.rsplit(":", 1)[-1].strip().lower()) in skeleton.joints}
    example = ", ".join(f'"{name}": "{joint}"' for name, joint in list(matches.items())[:3])
    if not example:
        example = f'"{names[0]}": "wrist"'
    return (f"map them to its joints in the sidecar's joint_map, e.g. \"joint_map\": "
            f"{{{example}, ...}}")


def check_joint_map_keys(spec: ClipSpec, named: Mapping[str, Collection[str]]) -> None:
    """Refuse ``joint_map`` keys that none of the clip's files names (a typo guard).

    ``named`` maps each of the clip's files to the names it holds.

    Raises
    ------
    InputError
        Naming the sidecar and ``joint_map``.
    """
    every = set().union(*named.values()) if named else set()
    for key in spec.joint_map:
        if key != IGNORE_OTHERS and key not in every:
            files = " or ".join(Path(f).name for f in named)
            held = sorted(every)
            shown = ", ".join(quoted(n) for n in held[:12]) + (", ..." if len(held) > 12
                                                              else "")
            raise InputError(spec.path, f"maps {quoted(key)}, which {files} does not name "
                             f"(it names {shown})", field="joint_map", clip_id=spec.clip_id)


def _distinct(values: np.ndarray) -> np.ndarray:
    """The distinct ``values`` in ascending order (``numpy.unique``).

    Rows in file order are usually in frame order already, and then need no sort.
    """
    if values.size and np.all(values[1:] >= values[:-1]):
        return values[np.concatenate([[True], values[1:] != values[:-1]])]
    return np.unique(values)


#: The largest finite float64: only an infinity's magnitude exceeds it.
_LARGEST_FINITE = float(np.finfo(np.float64).max)


def _exceeds(values: np.ndarray, limit: float) -> bool:
    """Whether a value of ``values`` ``(N,) float64`` has a magnitude above ``limit``.

    NaN (a missing value) exceeds nothing. Two reductions instead of a boolean array of
    ``N``: the checks then locate the first such value only in a file that has one.
    """
    if not values.size:
        return False
    return bool(np.fmax.reduce(values) > limit or np.fmin.reduce(values) < -limit)


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
    names: frozenset[str]
    fields: Mapping[str, str] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    sampling: str = VIDEO

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
        beyond = np.flatnonzero(self.frame >= MAX_FRAMES)
        if beyond.size:
            raise self.error(beyond[0], "frame", frame_limit_reason(int(self.frame[beyond[0]])))
        if n and self.n_frames <= self.frame.max():
            raise ValueError("n_frames must exceed every frame number")
        if self.n_frames > MAX_FRAMES:
            raise ValueError(f"n_frames must not exceed MAX_FRAMES ({MAX_FRAMES})")
        self._check_dense()
        key = self.frame * self.skeleton.n_joints + self.joint
        if np.all(key[1:] > key[:-1]):
            return
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

    def _check_dense(self) -> None:
        """Refuse frame numbers that are mostly invented or split by a stray empty run.

        See ``limits.is_sparse`` and ``limits.is_stray_run``.
        """
        filled = _distinct(self.frame)
        if self.n_rows and is_sparse(filled.size, self.n_frames):
            row = int(np.argmax(self.frame))
            raise self.error(
                row, "frame",
                f"frame {self.frame[row]} makes a clip of {self.n_frames:,} frames of which "
                f"only {filled.size} carry a point; number the frames from the clip's start "
                "(is this frame number a typo, or an id of a dataset's image?)")
        before, after = longest_empty_run(filled)
        if is_stray_run(before, after, filled.size):
            row = int(np.flatnonzero(self.frame == after)[0])
            raise self.error(
                row, "frame",
                f"frame {after} comes after {after - before - 1:,} frames without a point "
                f"(from frame {before + 1}), more than the {filled.size} frames that carry "
                "one: gap filling would invent them. Is the frame number a typo? Else split "
                "the track into two clips at the empty run")

    def _coordinates(self) -> dict[str, np.ndarray]:
        """The rows' coordinates by generic field name, ``(N,)`` each."""
        raise NotImplementedError

    def check_magnitude(self, limit: float, unit: str) -> None:
        """Refuse any coordinate whose magnitude exceeds ``limit`` (in ``unit``).

        Raises
        ------
        InputError
            At the first such coordinate, naming its row and field.
        """
        values = self._coordinates()
        if not any(_exceeds(column, limit) for column in values.values()):
            return
        arrays = np.stack(list(values.values()), axis=1)
        beyond = np.argwhere(np.abs(arrays) > limit)
        if beyond.size:
            row, col = beyond[0]
            raise self.error(row, list(values)[col], f"{arrays[row, col]:g} {unit} is not a "
                             f"plausible coordinate (limit {limit:g} {unit})")

    def _check_not_infinite(self, values: dict[str, np.ndarray]) -> None:
        if not any(_exceeds(column, _LARGEST_FINITE) for column in values.values()):
            return
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
    names
        Every joint name the file holds, those the ``joint_map`` ignores included (for
        :func:`check_joint_map_keys`).
    fields
        The source's names of the generic columns (``frame``, ``joint``, ``u``, ``v``,
        ``confidence``) where they differ; ``{joint}`` in a name stands for the joint.
    joint_names
        The source's name of each skeleton joint, for ``{joint}`` in ``fields``; empty
        for the canonical names.
    sampling
        :data:`~handdb.clip.VIDEO` (frames of one recording) or
        :data:`~handdb.clip.IMAGES` (independent images); becomes
        :attr:`handdb.clip.Clip.sampling`.
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

    @cached_property
    def uv(self) -> np.ndarray:
        """``(N, 2) float64`` pixels, read-only (built once: ingest reads it three times)."""
        uv = np.stack([self.u, self.v], axis=1)
        uv.flags.writeable = False
        return uv

    def _coordinates(self) -> dict[str, np.ndarray]:
        return {"u": self.u, "v": self.v}

    def check_pixels(self, reads_coordinates: bool) -> None:
        """Refuse a track normalised to the image instead of in pixels.

        Such a track's every point lies within :data:`NORMALISED_BOUND` pixels of the
        origin: a hand is more than two pixels across. This is the one check of it, for
        every 2D format.

        Parameters
        ----------
        reads_coordinates
            Whether the format reads the sidecar's ``coordinates`` (OpenPose, MediaPipe),
            which is then the remedy the message gives.

        Raises
        ------
        InputError
            At the point farthest from the origin, saying how to give pixels.
        """
        uv = self.uv
        seen = np.flatnonzero(finite_points(uv))
        if not seen.size or np.abs(uv[seen]).max() > NORMALISED_BOUND:
            return
        row = int(seen[np.argmax(np.abs(uv[seen]).max(axis=1))])
        remedy = ('the tool wrote normalised coordinates (OpenPose run with --keypoint_scale '
                  '3 or 4): add "coordinates": "normalized" (or, for OpenPose\'s [-1, 1], '
                  '"normalized_signed") and "image": {"width": W, "height": H} to the sidecar'
                  if reads_coordinates else
                  "multiply them by the image's width and height (MediaPipe's landmarks: "
                  "keep them in .mediapipe.csv or .mediapipe.json, which scale them by the "
                  'sidecar\'s "image")')
        raise self.error(row, "u", f"every point lies within {NORMALISED_BOUND:g} px of the "
                         "origin, so the coordinates are normalised to the image, not "
                         f"pixels: {remedy}")


@dataclass(frozen=True, kw_only=True)
class Positions(_Rows):
    """3D ground-truth points of one clip in long form, one row per (frame, joint).

    Attributes are those of :class:`Observations` without ``u, v, confidence`` and with
    ``xyz``: ``(N, 3) float64`` in the clip's units, every value finite: camera frame
    (x right, y down, z away from the camera) for ground truth, the capture's frame for
    3D markers.
    """

    xyz: np.ndarray

    def __post_init__(self) -> None:
        self._check_rows()
        if self.xyz.shape != (self.n_rows, 3):
            raise ValueError(f"xyz must have shape ({self.n_rows}, 3)")
        self._check_not_infinite(dict(zip("xyz", self.xyz.T, strict=True)))
        if not self.xyz.size or not np.isnan(self.xyz.min()):
            return
        missing = np.argwhere(np.isnan(self.xyz))
        if missing.size:
            row, axis = missing[0]
            raise self.error(row, "xyz"[axis], "is empty; ground truth rows need x, y and z "
                             "(leave out the row of a joint without ground truth)")

    def _coordinates(self) -> dict[str, np.ndarray]:
        return dict(zip("xyz", self.xyz.T, strict=True))


def single_file_rows(path: str | Path, n: int) -> tuple[np.ndarray, tuple[str, ...]]:
    """``source`` and ``files`` for rows that all come from the one file ``path``."""
    return np.zeros(n, dtype=np.int64), (str(path),)
