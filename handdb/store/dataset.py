"""A stored clip as an :class:`xarray.Dataset`, in the layout of ``movement``'s poses.

:func:`load_clip` reads one clip's rows of ``clips`` and ``joints_3d`` and gives them
dimensions ``time``, ``keypoints`` and ``space`` (``x, y, z``), the layout of the
``movement`` package's pose datasets for one individual, so that its kinematics and
plots work on handdb's clips. :func:`points_frame` gives the same values as a pandas
frame, one row per frame and joint; :func:`load_truth` the clip's ground truth as an array.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from handdb.errors import UnknownNameError
from handdb.hand.skeletons import load_skeleton
from handdb.store import tables
from handdb.store.database import Store

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

#: Per-point columns of ``joints_3d`` that become variables over ``(time, keypoints)``,
#: with their missing value.
POINT_VARIABLES = {"u": np.nan, "v": np.nan, "confidence": np.nan, "observed": False,
                   "filled": False, "sign_confidence": np.nan, "residual": np.nan,
                   "flagged": False}

#: Columns of ``clips`` kept as the dataset's attributes (NULL ones are left out).
CLIP_ATTRIBUTES = ("clip_id", "subject", "hand", "skeleton", "fps", "units", "camera_model",
                   "fx", "fy", "cx", "cy", "image_width", "image_height", "source_format",
                   "gap_fill_method", "lift_method", "flagged")


def load_clip(db: str | Store, clip_id: str) -> xr.Dataset:
    """Return the stored clip ``clip_id`` as an xarray dataset.

    Parameters
    ----------
    db
        Database folder or fsspec URL, or a :class:`~handdb.store.database.Store`.
    clip_id
        A clip of ``clips``.

    Returns
    -------
    xarray.Dataset
        Dimensions ``time`` (``T``; coordinates in seconds, and ``frame``), ``keypoints``
        (the skeleton's joints) and ``space`` (``x, y, z``). ``position`` ``(time,
        keypoints, space)``: the lifted joints, camera frame (x right, y down, z away
        from the camera), the clip's units; ``u``, ``v`` (the 2D point, observed or
        filled, pixels), ``confidence``, ``observed``, ``filled``, ``sign_confidence``,
        ``residual`` and ``flagged`` ``(time, keypoints)`` as in ``joints_3d``; NaN (or
        ``False``) where the table has no row. Attributes: the clip's sidecar facts
        (``fps``, ``units``, camera, hand, ...), ``flag_reasons`` and ``source="handdb"``.

    Raises
    ------
    DatabasePathError
        When there is no database at ``db``.
    UnknownNameError
        When the database holds no clip ``clip_id``.
    """
    import xarray as xr

    from handdb.store.query import connect

    store = db if isinstance(db, Store) else Store(str(db))
    store.check_readable()
    with connect(store, read_only=True) as con:
        clips = con.sql("SELECT * FROM clips WHERE clip_id = ?",
                        params=[clip_id]).to_arrow_table()
        if clips.num_rows == 0:
            known = tuple(c for (c,) in con.execute(
                "SELECT clip_id FROM clips ORDER BY clip_id").fetchall())
            raise UnknownNameError("clip", clip_id, known)
        rows = con.sql("SELECT * FROM joints_3d WHERE clip_id = ? ORDER BY frame, joint_index",
                       params=[clip_id]).to_arrow_table()
    clip = clips.to_pylist()[0]
    joints = load_skeleton(clip["skeleton"]).joints
    shape = (clip["n_frames"], len(joints))
    point_variables = {
        name: (("time", "keypoints"), tables.per_point(rows, (name,), shape, missing)[..., 0])
        for name, missing in POINT_VARIABLES.items()}
    attrs = {key: clip[key] for key in CLIP_ATTRIBUTES if clip[key] is not None}
    attrs |= {"flag_reasons": list(clip["flag_reasons"]), "source": "handdb"}
    frames = np.arange(shape[0])
    return xr.Dataset(
        data_vars={
            "position": (("time", "keypoints", "space"),
                         tables.per_point(rows, ("x", "y", "z"), shape),
                         {"units": clip["units"], "frame": "camera: x right, y down, z away"}),
            **point_variables,
        },
        coords={"time": ("time", frames / clip["fps"], {"units": "s"}),
                "frame": ("time", frames), "keypoints": list(joints),
                "space": ["x", "y", "z"]},
        attrs=attrs,
    )


def load_truth(db: str | Store, clip_id: str, shape: tuple[int, int]) -> np.ndarray | None:
    """The stored ground truth of ``clip_id``, ``(T, J, 3) float64``, or ``None`` if none.

    Parameters
    ----------
    db
        Database folder or fsspec URL, or a :class:`~handdb.store.database.Store`.
    clip_id
        A clip of ``clips``.
    shape
        ``(T, J)``: the clip's frames and joints (:func:`load_clip`'s ``time`` and
        ``keypoints``). Positions are in the clip's units, camera frame; NaN where
        ``truth_3d`` has no row.
    """
    from handdb.store.query import connect

    store = db if isinstance(db, Store) else Store(str(db))
    with connect(store, read_only=True) as con:
        rows = con.sql("SELECT frame, joint_index, x, y, z FROM truth_3d WHERE clip_id = ?",
                       params=[clip_id]).to_arrow_table()
    if rows.num_rows == 0:
        return None
    return tables.per_point(rows, ("x", "y", "z"), shape).astype(np.float64, copy=False)


def points_frame(dataset: xr.Dataset) -> pd.DataFrame:
    """One row per frame and joint of a :func:`load_clip` dataset, as a pandas frame.

    Columns: ``time`` (s), ``keypoints``, ``frame``, ``x``, ``y``, ``z`` (the clip's units)
    and the per-point variables (``u``, ``v`` in pixels, ``confidence``, ...).
    """
    per_point = dataset.drop_dims("space").to_dataframe()
    return per_point.join(dataset.position.to_series().unstack("space")).reset_index()
