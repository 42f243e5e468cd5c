"""Clips with complete tracks for the gap-filling evaluation, and where its results go.

Only a clip whose every point is observed can be scored: its points are hidden on purpose
and the fill compared with them. Such clips come from three places, each named by a small
*source* that loads the clip when asked (so a flow can pass sources to its tasks):

* :class:`SyntheticSource`: a synthesized clip (``synthetic-<motion>-seed<seed>``);
* :class:`DatabaseSource`: a clip of a handdb database, read from its ``clips`` and
  ``joints_3d`` tables (and ``truth_3d`` when present);
* :class:`InboxSource`: a clip of an inbox, read by the inbox readers.

:func:`store_evaluation` writes a clip's ``gapfill_eval`` rows into a database (partition
per clip) and its chart to ``<db>/reports/<clip_id>/gapfill.png``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from handdb.errors import InputError
from handdb.gapfill.evaluate import Evaluation, plot_masks
from handdb.gapfill.registry import DEFAULT_METHOD, METHODS, THESIS
from handdb.hand.skeletons import Skeleton, load_skeleton
from handdb.ingest.inbox import ClipEntry, load_clip
from handdb.store.database import Store

#: Table of the evaluation's rows.
EVAL_TABLE = "gapfill_eval"
#: Folder of per-clip reports in a database, and the evaluation chart's file name.
REPORTS = "reports"
CHART = "gapfill.png"


@dataclass(frozen=True)
class FullClip:
    """A clip with complete 2D tracks.

    Attributes
    ----------
    clip_id
        Names the clip (and its database partition).
    uv
        ``(T, J, 2) float64``, pixels, no NaN.
    skeleton
        The clip's skeleton.
    xyz
        ``(T, J, 3) float64`` camera-frame joints when known (needed by the occlusion
        mask), else ``None``.
    """

    clip_id: str
    uv: np.ndarray
    skeleton: Skeleton
    xyz: np.ndarray | None = None


@dataclass(frozen=True)
class SyntheticSource:
    """A synthesized clip (see :func:`handdb.synthetic.clips.synthesize_clip`)."""

    motion: str
    n_frames: int
    seed: int
    skeleton: str = "mediapipe21"

    @property
    def clip_id(self) -> str:
        """``synthetic-<motion>-seed<seed>``."""
        return f"synthetic-{self.motion}-seed{self.seed}"

    def load(self) -> FullClip | None:
        """Synthesize the clip."""
        from handdb.synthetic.clips import synthesize_clip

        clip = synthesize_clip(self.motion, self.n_frames, skeleton=self.skeleton, seed=self.seed)
        return FullClip(self.clip_id, clip.uv, load_skeleton(self.skeleton), clip.xyz)


def _dense(table: pa.Table, n_frames: int, n_joints: int, columns: Sequence[str]) -> np.ndarray:
    """Scatter rows (``frame``, ``joint_index``, ``columns``) into ``(T, J, C)``, NaN elsewhere."""
    dense = np.full((n_frames, n_joints, len(columns)), np.nan)
    frame = table.column("frame").to_numpy()
    joint = table.column("joint_index").to_numpy()
    dense[frame, joint] = np.stack(
        [table.column(c).to_numpy(zero_copy_only=False) for c in columns], axis=-1)
    return dense


@dataclass(frozen=True)
class DatabaseSource:
    """A clip of the database at ``db``."""

    db: str
    clip_id: str

    def load(self) -> FullClip | None:
        """Read the clip's points and skeleton; ``None`` when a point is not observed."""
        store = Store(self.db)
        clip_row = store.read("clips", self.clip_id)
        joints = store.read("joints_3d", self.clip_id)
        if clip_row is None or joints is None:
            return None
        skeleton = load_skeleton(clip_row.column("skeleton")[0].as_py())
        n_frames = int(clip_row.column("n_frames")[0].as_py())
        observed = _dense(joints, n_frames, skeleton.n_joints, ["observed"])[..., 0]
        if not (observed == 1).all():
            return None
        uv = _dense(joints, n_frames, skeleton.n_joints, ["u", "v"])
        truth = store.read("truth_3d", self.clip_id)
        xyz = None if truth is None else _dense(truth, n_frames, skeleton.n_joints,
                                                ["x", "y", "z"])
        if xyz is not None and not np.isfinite(xyz).all():
            xyz = None
        return FullClip(self.clip_id, uv, skeleton, xyz)


@dataclass(frozen=True)
class InboxSource:
    """A clip of an inbox."""

    entry: ClipEntry

    @property
    def clip_id(self) -> str:
        """The inbox clip's id."""
        return self.entry.clip_id

    def load(self) -> FullClip | None:
        """Read the clip; ``None`` when a point is not observed or the files are refused."""
        try:
            clip = load_clip(self.entry)
        except InputError:
            return None
        if not clip.observed.all():
            return None
        truth = clip.truth if clip.truth is not None and np.isfinite(clip.truth).all() else None
        return FullClip(clip.clip_id, clip.uv, clip.skeleton, truth)


ClipSource = SyntheticSource | DatabaseSource | InboxSource


def database_sources(db: str) -> list[DatabaseSource]:
    """List the database's clips whose points were all observed (by ``clips``).

    A clip's ``n_observed`` must equal its frames times joints; :meth:`DatabaseSource.load`
    checks the points themselves.
    """
    clips = Store(db).read_table("clips").to_pydict()
    return [
        DatabaseSource(db, clip_id)
        for clip_id, seen, frames, joints in zip(
            clips["clip_id"], clips["n_observed"], clips["n_frames"], clips["n_joints"],
            strict=True)
        if seen == frames * joints
    ]


def chart_path(store: Store, clip_id: str) -> str:
    """Where the clip's gap-filling chart goes in the database."""
    return store.path(REPORTS, clip_id, CHART)


def store_evaluation(
    store: Store, clip: FullClip, evaluation: Evaluation, methods: Sequence[str]
) -> str:
    """Write a clip's ``gapfill_eval`` rows and its chart (one panel per mask) into ``store``.

    The chart, like the thesis's Figure 4.6, draws the thesis's methods among ``methods``
    and the default last, on top (all of ``methods`` when none of those was scored).

    Returns
    -------
    str
        The chart's path on the store's filesystem.
    """
    store.write(EVAL_TABLE, clip.clip_id, evaluation.table)
    charted = [m for m in methods if METHODS[m].family == THESIS]
    charted += [DEFAULT_METHOD] if DEFAULT_METHOD in methods else []
    path = chart_path(store, clip.clip_id)
    store.fs.makedirs(store.path(REPORTS, clip.clip_id), exist_ok=True)
    with store.fs.open(path, "wb") as fh:
        plot_masks(evaluation, clip.skeleton, fh, methods=charted or list(methods),
                   title=f"{clip.clip_id}: gap-filling error per frame")
    return path

