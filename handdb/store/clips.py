"""A committed clip read back from its tables as a :class:`~handdb.clip.Clip`.

The ``clips`` row holds the sidecar and the clip's size; ``tracks_2d``, ``truth_3d`` and
``markers_3d`` hold its points exactly as ingest read them, so the clip comes back as it was.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa

from handdb.clip import NO_CAMERA, Clip, ClipSpec
from handdb.errors import StoreError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest.sidecar import parse_sidecar, parse_sidecar_text
from handdb.store.database import Store


def read_partition(store: Store, table: str, clip_id: str) -> pa.Table:
    """The rows of ``clip_id`` in ``table``.

    Raises
    ------
    StoreError
        If the clip has no partition there.
    """
    data = store.read(table, clip_id)
    if data is None:
        raise StoreError(f"clip '{clip_id}' has no {table} rows in {store.url}")
    return data


def scatter(rows: pa.Table, shape: tuple[int, ...], columns: tuple[str, ...]) -> np.ndarray:
    """Rows ``(frame, joint_index, *columns)`` as a dense ``shape`` array, NaN elsewhere.

    ``shape`` is ``(T, J)`` for one column, ``(T, J, C)`` for ``C`` columns.
    """
    dense = np.full(shape, np.nan)
    frame = rows.column("frame").to_numpy()
    joint = rows.column("joint_index").to_numpy()
    values = np.stack([rows.column(c).to_numpy(zero_copy_only=False).astype(np.float64)
                       for c in columns], axis=-1)
    dense[frame, joint] = values.reshape((len(rows),) + shape[2:])
    return dense


def stored_clip(store: Store, clip_id: str, *, sidecar: str | Path | None = None,
                content_hash: str | None = None) -> Clip:
    """Read the committed clip ``clip_id`` back.

    Parameters
    ----------
    store
        The database.
    clip_id
        The clip.
    sidecar
        The clip's sidecar file (it must be the one the clip was built from); without it
        the sidecar stored in ``clips`` is used, and ``spec.path`` names the database.
    content_hash
        The clip's content hash, when known; else the stored one.

    Raises
    ------
    StoreError
        If the clip or one of its tables is not in the database.
    """
    row = read_partition(store, "clips", clip_id).to_pylist()[0]
    three_d = row["camera_model"] == NO_CAMERA
    spec: ClipSpec
    if sidecar is not None:
        spec = parse_sidecar(sidecar, clip_id, three_d=three_d)
    else:
        spec = parse_sidecar_text(row["sidecar"], store.uri("clips", f"{clip_id}.parquet"),
                                  clip_id, three_d=three_d)
    skeleton = load_skeleton(spec.skeleton)
    shape = (int(row["n_frames"]), skeleton.n_joints)
    tracks = read_partition(store, "tracks_2d", clip_id)
    truth = (scatter(read_partition(store, "truth_3d", clip_id), shape + (3,), ("x", "y", "z"))
             if row["has_truth"] else None)
    markers = (scatter(read_partition(store, "markers_3d", clip_id), shape + (3,),
                       ("x", "y", "z")) if three_d else None)
    return Clip(spec=spec, skeleton=skeleton, uv=scatter(tracks, shape + (2,), ("u", "v")),
                confidence=scatter(tracks, shape, ("confidence",)), truth=truth,
                markers=markers, source_format=row["source_format"],
                source_files=tuple(row["source_files"]),
                content_hash=content_hash or row["content_hash"], sampling=row["sampling"])
