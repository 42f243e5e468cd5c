import numpy as np
import pytest

from handdb.gapfill import THESIS, fill_gaps, method_names
from handdb.gapfill.evaluate import (
    RANDOM_MASK,
    THESIS_MASK,
    evaluate_clip,
    overall_rmse,
    plot_errors,
)
from handdb.gapfill.gaps import find_gaps
from handdb.gapfill.masks import THESIS_TABLE_4_2, random_gaps_mask, thesis_table_4_2_mask
from handdb.gapfill.occlusion import occlusion_mask
from handdb.hand.skeletons import load_skeleton
from handdb.store import tables
from handdb.synthetic.clips import synthesize_clip


def test_table_4_2_mask_on_the_thesis_skeleton(thesis21):
    mask = thesis_table_4_2_mask(thesis21)
    ids = np.asarray(thesis21.ids)
    for j, point in enumerate(ids):
        expected = np.zeros(100, dtype=bool)
        if point in THESIS_TABLE_4_2:
            first, last = THESIS_TABLE_4_2[point]
            expected[first:last + 1] = True
        assert np.array_equal(mask[:, j], expected), point


def test_table_4_2_mask_is_mapped_by_joint_name(mediapipe):
    mask = thesis_table_4_2_mask(mediapipe)
    assert np.flatnonzero(mask[:, mediapipe.index("index_dip")]).tolist() == list(range(37, 48))
    assert not mask[:, mediapipe.index("wrist")].any()
    assert not mask[:, mediapipe.index("thumb_cmc")].any()       # not a thesis point
    assert mask.sum() == sum(b - a + 1 for a, b in THESIS_TABLE_4_2.values())


def test_random_gaps_are_interior_seeded_and_bounded():
    mask = random_gaps_mask(400, 21, seed=7)
    assert np.array_equal(mask, random_gaps_mask(400, 21, seed=7))
    assert not np.array_equal(mask, random_gaps_mask(400, 21, seed=8))
    gaps = find_gaps(mask)
    assert gaps.interior.all()
    assert 1 <= len(gaps) <= 40


def test_evaluation_rows_conform_and_the_chart_is_written(rapid_clip, mediapipe, tmp_path):
    methods = ("previous", "pchip", "auto")
    evaluation = evaluate_clip("rapid", rapid_clip.uv[:200], mediapipe, methods=methods)
    table = evaluation.table
    assert table.schema.equals(tables.schema("gapfill_eval"), check_metadata=False)
    assert set(table.column("mask").to_pylist()) == {THESIS_MASK, RANDOM_MASK}
    assert set(table.column("method").to_pylist()) == set(methods)
    hidden = evaluation.hidden[THESIS_MASK]
    rows = table.filter(np.array(table.column("mask").to_pylist()) == THESIS_MASK)
    assert sum(rows.column("n_filled").to_pylist()) == hidden.sum() * len(methods)
    png = plot_errors(evaluation, THESIS_MASK, mediapipe, tmp_path / "fig.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _rmse(uv, hidden, skeleton, method):
    filled = fill_gaps(uv, ~hidden, skeleton, method).uv
    return float(np.sqrt(np.mean(np.sum((filled - uv) ** 2, axis=-1)[hidden])))


def test_default_beats_every_thesis_method_under_random_gaps(rapid_clip, mediapipe):
    hidden = random_gaps_mask(400, mediapipe.n_joints, seed=1)
    default = _rmse(rapid_clip.uv, hidden, mediapipe, "auto")
    best_thesis = min(_rmse(rapid_clip.uv, hidden, mediapipe, m) for m in method_names(THESIS))
    assert best_thesis / default > 4.0
    assert _rmse(rapid_clip.uv, hidden, mediapipe, "linear") / default > 3.0


def test_default_beats_the_thesis_on_the_real_capture(dhg_mm):
    dhg = load_skeleton("dhg22")
    uv = dhg_mm[..., :2]
    evaluation = evaluate_clip("dhg", uv, dhg, masks=(THESIS_MASK,),
                               methods=("auto", *method_names(THESIS)))
    rmse = overall_rmse(evaluation)
    best_thesis = min(rmse[(THESIS_MASK, m)] for m in method_names(THESIS))
    assert best_thesis / rmse[(THESIS_MASK, "auto")] > 5.0


def test_a_clenching_fist_hides_its_fingertips_from_the_camera(mediapipe):
    clip = synthesize_clip("clench", 40, seed=0)
    hidden = occlusion_mask(clip.xyz[[0, -1]], mediapipe)
    tips = [mediapipe.index(f"{f}_tip") for f in ("index", "middle", "ring", "little")]
    assert not hidden[0].any()
    assert hidden[1, tips].any()
    assert hidden[1].sum() >= 5
    assert not hidden[:, mediapipe.index("wrist")].any()


@pytest.mark.parametrize("n_frames", [60, 100])
def test_table_4_2_segments_cover_short_clips(rapid_clip, mediapipe, n_frames):
    evaluation = evaluate_clip("short", rapid_clip.uv[:n_frames], mediapipe,
                               masks=(THESIS_MASK,), methods=("previous",))
    assert evaluation.hidden[THESIS_MASK].shape == (n_frames, mediapipe.n_joints)
    assert np.isfinite(evaluation.errors[(THESIS_MASK, "previous")][
        evaluation.hidden[THESIS_MASK]]).all()
