import numpy as np
import pyarrow.compute as pc
import pytest

from handdb.errors import BoneLengthError
from handdb.hand.anatomy import BUCHHOLZ_1992, hand_length_proportions
from handdb.hand.skeletons import load_skeleton
from handdb.lengths.bone_lengths import (
    SOURCES,
    bone_lengths_table,
    clip_bone_lengths,
    lengths_from_ratios,
    most_stretched_frame,
)
from handdb.lengths.ratios import bone_ratios, joint_ratios, table1_measurements
from handdb.store.tables import empty, schema

#: Curl per frame (radians); frame 3 shows the flat, stretched hand.
CURL = np.array([0.9, 0.6, 0.3, 0.0, 0.4, 1.2])
FLAT_FRAME = 3


@pytest.fixture(scope="module")
def ratios():
    return joint_ratios(table1_measurements())


def test_reference_frame_gives_every_bone_from_one_length(make_clip, hand):
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0})
    truth = hand.true_lengths(clip.skeleton)
    assert most_stretched_frame(clip.uv, clip.skeleton) == FLAT_FRAME
    result = clip_bone_lengths(clip)
    sources = dict(zip(clip.skeleton.joints, result.sources, strict=True))
    assert sources["index_pip"] == "given" and result.lengths[6] == 49.0
    others = [j for j, s in enumerate(result.sources) if s == "reference_frame"]
    assert len(others) == clip.skeleton.n_joints - 2
    # index_pip is given as 49.0 mm where the synthetic hand has 49.0 mm within 0.1 %.
    expected = truth[others] * 49.0 / truth[6]
    np.testing.assert_allclose(result.lengths[others], expected, rtol=1e-9)
    assert np.isnan(result.lengths[clip.skeleton.root])


def test_truth_beats_the_reference_frame_and_given_beats_truth(make_clip, hand):
    clip = make_clip(CURL, bone_lengths={"thumb_tip": 20.0}, with_truth=True)
    result = clip_bone_lengths(clip)
    truth = hand.true_lengths(clip.skeleton)
    sources = set(result.sources) - {None}
    assert sources == {"given", "truth"}
    index = clip.skeleton.index("thumb_tip")
    assert result.lengths[index] == 20.0
    measured = [j for j, s in enumerate(result.sources) if s == "truth"]
    np.testing.assert_allclose(result.lengths[measured], truth[measured])
    assert (result.n_frames[measured] == CURL.size).all()


def test_hidden_finger_comes_from_ratios(make_clip, ratios):
    hidden = ("ring_dip", "ring_tip")
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0}, hidden=hidden)
    result = clip_bone_lengths(clip, ratios)
    skeleton = clip.skeleton
    mean, _ = bone_ratios(skeleton, ratios)
    ring_pip = result.lengths[skeleton.index("ring_pip")]
    for joint in hidden:
        j = skeleton.index(joint)
        assert result.sources[j] == "ratios"
        assert result.lengths[j] == pytest.approx(ring_pip / mean[skeleton.index("ring_pip")]
                                                  * mean[j])


def test_palm_bone_unseen_comes_from_anthropometry(make_clip, hand):
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0}, hidden=("little_mcp",))
    result = clip_bone_lengths(clip)
    skeleton = clip.skeleton
    little = skeleton.index("little_mcp")
    assert result.sources[little] == "anthropometric"
    proportion = hand_length_proportions(skeleton)[little]
    # The reference-frame bones are exact up to the scale the given index_pip sets.
    scale = 49.0 / hand.true_lengths(skeleton)[skeleton.index("index_pip")]
    assert result.lengths[little] == pytest.approx(proportion * hand.hand_length_mm * scale)
    assert "Buchholz" in result.details[little]


def test_no_scale_raises(make_clip):
    with pytest.raises(BoneLengthError, match="no bone length to scale"):
        clip_bone_lengths(make_clip(CURL))


def test_bone_without_any_source_raises(make_clip):
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0}, hidden=("thumb_cmc",))
    with pytest.raises(BoneLengthError, match="thumb_cmc") as info:
        clip_bone_lengths(clip)
    assert "bone_lengths" in str(info.value)




def test_lengths_from_ratios_average_the_known_phalanges(ratios):
    skeleton = load_skeleton("mediapipe21")
    mean, _ = bone_ratios(skeleton, ratios)
    known = np.full(skeleton.n_joints, np.nan)
    pip, dip = skeleton.index("middle_pip"), skeleton.index("middle_dip")
    known[pip], known[dip] = 50.0, 30.0
    lengths, total = lengths_from_ratios(skeleton, known, mean)
    expected_total = (50.0 / mean[pip] + 30.0 / mean[dip]) / 2
    assert total[skeleton.index("middle_tip")] == pytest.approx(expected_total)
    assert np.isnan(lengths[skeleton.index("index_tip")])
    assert np.isnan(lengths[skeleton.index("middle_mcp")])


def test_table_has_a_row_per_bone(make_clip):
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0}, with_truth=True)
    result = clip_bone_lengths(clip)
    table = bone_lengths_table(clip.clip_id, "s01", clip.skeleton, result)
    assert table.schema.equals(schema("bone_lengths"), check_metadata=False)
    assert table.num_rows == len(clip.skeleton.bone_names)
    assert set(table["bone"].to_pylist()) == set(clip.skeleton.bone_names)
    assert set(table["source"].to_pylist()) <= set(SOURCES)
    given = table.filter(pc.equal(table["source"], "given"))
    assert given["n_frames"].null_count == 1 and given["units"][0].as_py() == "mm"


def test_buchholz_middle_finger_spans_the_hand():
    middle = BUCHHOLZ_1992["middle"]
    proportions = hand_length_proportions(load_skeleton("mediapipe21"))
    chain = load_skeleton("mediapipe21").finger_chain("middle")
    assert proportions[chain].sum() == pytest.approx(1.0)
    assert proportions[chain[1]] == middle[1]


def test_empty_ratio_table_falls_back_to_table1(make_clip):
    clip = make_clip(CURL, bone_lengths={"index_pip": 49.0}, hidden=("ring_tip",))
    result = clip_bone_lengths(clip, empty("joint_ratios"))
    assert result.sources[clip.skeleton.index("ring_tip")] == "ratios"
    assert result.lengths == pytest.approx(clip_bone_lengths(clip).lengths, nan_ok=True)
