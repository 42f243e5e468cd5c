import math
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from scipy import stats

from handdb.errors import ClipDataError
from handdb.ingest.xray import read_xray
from handdb.lengths.ratios import (
    joint_ratios,
    paper_discrepancies,
    place_joints,
    relative_lengths,
    table1_measurements,
)

#: Figures printed by Chaudhry et al. for the index ("grooming") finger.
PAPER_INDEX_J1_RATIOS_TEXT = (0.4865, 0.4728, 0.4862, 0.5047, 0.4728)


def _row(ratios, finger, segment, cohort="all"):
    mask = pc.and_(pc.and_(pc.equal(ratios["cohort"], cohort), pc.equal(ratios["finger"], finger)),
                   pc.equal(ratios["segment"], segment))
    rows = ratios.filter(mask).to_pylist()
    assert len(rows) == 1
    return rows[0]


@pytest.fixture(scope="module")
def table1():
    return table1_measurements()


def test_table1_is_complete(table1):
    assert table1.num_rows == 5 * (4 * 3 + 2)
    assert sorted(set(table1["image_id"].to_pylist())) == ["1a", "1b", "1c", "1d", "1e"]


def test_index_finger_reproduces_the_paper(table1):
    ratios = joint_ratios(table1)
    j1 = _row(ratios, "index", "J1")
    assert j1["n"] == 5
    assert round(j1["mean"], 4) == 0.4846
    assert round(j1["min"], 4) == 0.4728
    assert round(j1["max"], 4) == 0.5047
    assert round(j1["range"], 4) == 0.0319
    assert round(_row(ratios, "index", "J2")["mean"], 4) == 0.2726


def test_per_image_ratios_match_the_text(table1):
    relative = relative_lengths(table1, decimals=4)
    j1 = relative.filter(pc.and_(pc.equal(relative["finger"], "index"),
                                 pc.equal(relative["segment"], "J1"))).sort_by("image_id")
    # Table 1 as printed gives 0.4867 for image 1a; the text's 0.4865 needs J3 = 169.97.
    assert j1["ratio"].to_pylist() == [0.4867, *PAPER_INDEX_J1_RATIOS_TEXT[1:]]
    assert round(339.96 / (339.96 + 188.83 + 169.97), 4) == PAPER_INDEX_J1_RATIOS_TEXT[0]
    totals = j1["total"].to_pylist()
    assert totals[1:] == pytest.approx([724.41, 739.78, 826.53, 793.68])


def test_last_segment_completes_the_finger(table1):
    ratios = joint_ratios(table1, decimals=None)
    for finger, segments in (("index", ("J1", "J2", "J3")), ("thumb", ("J1", "J2"))):
        total = sum(_row(ratios, finger, s)["mean"] for s in segments)
        assert total == pytest.approx(1.0)


def test_confidence_interval_is_the_t_interval(table1):
    relative = relative_lengths(table1)
    ring = relative.filter(pc.and_(pc.equal(relative["finger"], "ring"),
                                   pc.equal(relative["segment"], "J2")))
    values = np.round(ring["ratio"].to_numpy(), 4)
    low, high = stats.t.interval(0.95, len(values) - 1, loc=values.mean(),
                                 scale=stats.sem(values))
    row = _row(joint_ratios(table1), "ring", "J2")
    assert row["std"] == pytest.approx(values.std(ddof=1))
    assert (row["ci_low"], row["ci_high"]) == pytest.approx((low, high))


def test_discrepancies_are_recomputed_from_table1():
    mean, j3 = paper_discrepancies()
    assert mean.printed == 0.4946 and round(mean.recomputed, 4) == 0.4846
    assert j3.printed == 169.97 and j3.recomputed == 169.67
    assert "0.4946" in str(mean) and "0.4846" in str(mean)
    assert "169.97" in str(j3) and "169.67" in str(j3)


def test_cohorts_by_sex_and_age_band(tmp_path: Path):
    lines = ["image_id,finger,segment,length,sex,age"]
    hands = {"a": ("F", 25, (40, 20, 20)), "b": ("F", 31, (44, 18, 18)),
             "c": ("M", 45, (50, 30, 20)), "d": ("M", "", (45, 30, 25))}
    for image, (sex, age, lengths) in hands.items():
        lines += [f"{image},index,J{k + 1},{v},{sex},{age}" for k, v in enumerate(lengths)]
    path = tmp_path / "cohorts.xray.csv"
    path.write_text("\n".join(lines) + "\n")
    ratios = joint_ratios(read_xray(path)[0], decimals=None)
    cohorts = set(ratios["cohort"].to_pylist())
    assert cohorts == {"all", "sex:f", "sex:m", "age:18-39", "age:40-59"}
    female = _row(ratios, "index", "J1", "sex:f")
    assert female["n"] == 2 and female["mean"] == pytest.approx((0.5 + 0.55) / 2)
    older = _row(ratios, "index", "J1", "age:40-59")
    assert older["n"] == 1 and older["mean"] == pytest.approx(0.5)
    assert older["std"] is None and older["ci_low"] is None
    assert _row(ratios, "index", "J1")["n"] == 4


def test_place_joints_scales_the_ratios(table1):
    ratios = joint_ratios(table1)
    j1, j2, j3 = place_joints("index", 1000.0, ratios)
    assert round(j1.mean, 1) == 484.6
    assert (round(j1.min, 1), round(j1.max, 1), round(j1.range, 1)) == (472.8, 504.7, 31.9)
    assert j2.start == pytest.approx(j1.mean) and j3.start == pytest.approx(j1.mean + j2.mean)
    assert j1.mean + j2.mean + j3.mean == pytest.approx(1000.0, abs=0.1)
    assert [p.segment for p in place_joints("thumb", 10.0, ratios)] == ["J1", "J2"]


@pytest.mark.parametrize("total", [0.0, -1.0, math.nan])
def test_place_joints_refuses_a_bad_total(table1, total):
    with pytest.raises(ValueError, match="greater than 0"):
        place_joints("index", total, joint_ratios(table1))


def test_place_joints_names_a_missing_cohort(table1):
    with pytest.raises(ClipDataError, match="sex:f"):
        place_joints("index", 1.0, joint_ratios(table1), cohort="sex:f")


def test_images_of_different_files_are_kept_apart(tmp_path: Path):
    paths = []
    for name, lengths in (("one", (50, 30, 20)), ("two", (40, 40, 20))):
        path = tmp_path / f"{name}.xray.csv"
        path.write_text("image_id,finger,segment,length\n" + "".join(
            f"x1,index,J{k + 1},{v}\n" for k, v in enumerate(lengths)))
        paths.append(path)
    measurements = pa.concat_tables([read_xray(p)[0] for p in paths])
    j1 = _row(joint_ratios(measurements), "index", "J1")
    assert j1["n"] == 2 and j1["mean"] == pytest.approx(0.45)
