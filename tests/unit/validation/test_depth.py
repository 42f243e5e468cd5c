import numpy as np
import pytest

from handdb.hand.skeletons import load_skeleton
from handdb.lifting import LiftResult
from handdb.validation.depth import (
    _column_statistics,
    clip_summary,
    comparison_chart,
    markdown_summary,
    validation_table,
)


@pytest.fixture
def clip():
    skeleton = load_skeleton("mediapipe21")
    rng = np.random.default_rng(4)
    truth = rng.normal(scale=0.02, size=(50, skeleton.n_joints, 3))     # metres
    estimate = truth + rng.normal(scale=0.004, size=truth.shape)
    estimate[7, 3] = np.nan
    return skeleton, truth, estimate


def test_table_equals_a_direct_computation(clip):
    skeleton, truth, estimate = clip
    result = LiftResult(xyz=estimate, sign_confidence=np.full(truth.shape[:2], np.nan),
                        length_inconsistency=np.zeros(truth.shape[:2]),
                        scale=np.ones(len(truth)), method="noisy")
    table = validation_table("c1", truth, {"noisy": result, "same": truth}, skeleton, "m")
    assert table.num_rows == 2 * skeleton.n_joints
    rows = {(r["method"], r["joint"]): r for r in table.to_pylist()}

    joint = 3
    dz = np.abs((estimate[:, joint, 2] - estimate[:, 0, 2]) - (truth[:, joint, 2] - truth[:, 0, 2]))
    dz = dz[np.isfinite(dz)]
    row = rows[("noisy", skeleton.joints[joint])]
    assert row["n"] == 49
    assert row["dz_min"] == pytest.approx(dz.min())
    assert row["dz_max"] == pytest.approx(dz.max())
    assert row["dz_mean"] == pytest.approx(dz.mean())
    assert row["dz_std"] == pytest.approx(dz.std())

    parent = skeleton.parents[joint]
    true_bone = truth[:, joint, 2] - truth[:, parent, 2]
    est_bone = estimate[:, joint, 2] - estimate[:, parent, 2]
    counted = (np.abs(true_bone) >= 0.005) & np.isfinite(est_bone)
    assert row["n_sign"] == counted.sum()
    assert row["sign_accuracy"] == pytest.approx(
        np.mean(np.sign(true_bone[counted]) == np.sign(est_bone[counted])))
    position = np.linalg.norm((estimate[:, joint] - estimate[:, :1].squeeze(1))
                              - (truth[:, joint] - truth[:, 0]), axis=-1)
    assert row["mpjpe"] == pytest.approx(np.nanmean(position))

    exact = rows[("same", skeleton.joints[joint])]
    assert exact["dz_max"] == 0.0 and exact["sign_accuracy"] == 1.0
    root = rows[("noisy", skeleton.joints[skeleton.root])]
    assert root["n_sign"] is None and root["dz_max"] == 0.0


def test_summary_markdown_and_chart(clip):
    skeleton, truth, estimate = clip
    table = validation_table("c1", truth, {"noisy": estimate, "same": truth}, skeleton, "m")
    summary = clip_summary(table)
    assert summary["same"]["dz_mean"] == 0.0
    assert summary["noisy"]["dz_mean"] > 0.0
    text = markdown_summary("c1", table)
    assert "| noisy |" in text and "c1" in text
    png = comparison_chart("c1", table, skeleton)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("n_frames", [1, 3, 300])
def test_column_statistics_are_numpys_nan_reductions_bit_for_bit(n_frames):
    rng = np.random.default_rng(n_frames)
    values = np.abs(rng.normal(0.0, 10.0, (n_frames, 6))) * np.logspace(-3, 3, 6)
    values[rng.random(values.shape) < 0.3] = np.nan
    values[:, 2] = np.nan
    values[0, 4] = 7.25
    some = np.isfinite(values).any(axis=0)
    got = _column_statistics(values)
    for reduce, column in zip((np.nanmin, np.nanmax, np.nanmean, np.nanstd), got, strict=True):
        expected = np.full(values.shape[1], np.nan)
        expected[some] = reduce(values[:, some], axis=0)
        assert column.tobytes() == expected.tobytes()
    assert _column_statistics(values, spread=False)[2].tobytes() == got[2].tobytes()
