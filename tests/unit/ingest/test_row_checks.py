"""The row checks' quick pass (a reduction per column) finds what the located check finds.

``Observations`` and ``Positions`` first ask whether any value is infinite, beyond a
magnitude or missing, and only then look for the first such value; the message must still
name the first row and field, whatever NaN (missing points) lie around it.
"""

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest.inbox import _dense
from handdb.ingest.observations import Observations, Positions, single_file_rows


def _rows(skeleton, n_rows, n_joints=3):
    frame = np.repeat(np.arange(n_rows // n_joints), n_joints).astype(np.int64)
    joint = np.tile(np.arange(n_joints), n_rows // n_joints).astype(np.int64)
    source, files = single_file_rows("f.csv", n_rows)
    return {"frame": frame, "joint": joint, "line": np.arange(2, n_rows + 2),
            "source": source, "files": files, "skeleton": skeleton,
            "n_frames": int(frame.max()) + 1, "names": frozenset()}


def _observations(skeleton, u, v):
    n = u.size
    return Observations(**_rows(skeleton, n), u=u, v=v, confidence=np.full(n, np.nan))


@pytest.mark.parametrize("bad", [np.inf, -np.inf])
def test_an_infinite_coordinate_among_missing_ones_is_named(mediapipe21, bad):
    u = np.array([np.nan, 1.0, 2.0, 3.0, 4.0, 5.0])
    v = np.array([np.nan, 1.0, 2.0, 3.0, bad, 5.0])
    u[3] = np.nan
    v[3] = np.nan
    with pytest.raises(InputError, match="is not a finite number") as caught:
        _observations(mediapipe21, u, v)
    assert (caught.value.line, caught.value.field) == (6, "v")


def test_the_first_coordinate_beyond_the_limit_is_named(mediapipe21):
    u = np.array([np.nan, 1.0, 2.0, -700.0, 4.0, 5.0])
    v = np.array([np.nan, 1.0, 2.0, 3.0, 900.0, 5.0])
    rows = _observations(mediapipe21, u, v)
    rows.check_magnitude(1000.0, "px")
    with pytest.raises(InputError, match="-700 px is not a plausible") as caught:
        rows.check_magnitude(600.0, "px")
    assert (caught.value.line, caught.value.field) == (5, "u")
    with pytest.raises(InputError, match="900 px is not a plausible") as caught:
        rows.check_magnitude(800.0, "px")
    assert (caught.value.line, caught.value.field) == (6, "v")


def test_an_all_missing_track_passes_the_magnitude_check(mediapipe21):
    nan = np.full(6, np.nan)
    _observations(mediapipe21, nan, nan.copy()).check_magnitude(1.0, "px")


def test_an_empty_truth_cell_is_named_after_finite_ones(mediapipe21):
    xyz = np.arange(18, dtype=np.float64).reshape(6, 3)
    xyz[4, 1] = np.nan
    with pytest.raises(InputError, match="ground truth rows need") as caught:
        Positions(**_rows(mediapipe21, 6), xyz=xyz)
    assert (caught.value.line, caught.value.field) == (6, "y")
    Positions(**_rows(mediapipe21, 6), xyz=np.zeros((6, 3)))


def test_uv_is_read_only(mediapipe21):
    rows = _observations(mediapipe21, np.arange(6.0), np.arange(6.0))
    assert rows.uv is rows.uv
    with pytest.raises(ValueError, match="read-only"):
        rows.uv[0, 0] = 1.0


@pytest.mark.parametrize("keep", ["all", "gaps", "shuffled"])
def test_dense_arrays_are_the_scatter_of_the_rows(mediapipe21, keep):
    rng = np.random.default_rng(3)
    n_frames, n_joints = 7, mediapipe21.n_joints
    frame, joint = (a.ravel() for a in np.meshgrid(np.arange(n_frames), np.arange(n_joints),
                                                    indexing="ij"))
    order = np.arange(frame.size)
    if keep == "gaps":
        order = np.sort(rng.choice(frame.size, frame.size - 9, replace=False))
    elif keep == "shuffled":
        order = rng.permutation(frame.size)
    rows = Positions(frame=frame[order], joint=joint[order], line=order + 2,
                     source=np.zeros(order.size, np.int64), files=("f.csv",),
                     skeleton=mediapipe21, n_frames=n_frames, names=frozenset(),
                     xyz=rng.normal(size=(order.size, 3)))
    expected = np.full((n_frames, n_joints, 3), np.nan)
    expected[rows.frame, rows.joint] = rows.xyz
    dense = _dense(rows, rows.xyz, n_frames)
    np.testing.assert_array_equal(dense, expected)
    assert dense.flags.writeable and not np.shares_memory(dense, rows.xyz)
