"""Every bone of a clip gets a length, from what is known and from the whole clip."""

import json
from dataclasses import replace

import numpy as np
import pyarrow.compute as pc
import pytest

from handdb.hand.anatomy import hand_length_proportions
from handdb.hand.skeletons import load_skeleton
from handdb.lengths.bone_lengths import SOURCES, bone_lengths_table, clip_bone_lengths
from handdb.lengths.estimate import (
    Estimate,
    combine,
    consistency_ratio,
    hand_proportions,
    image_proportions,
    palm_bones,
    ratio_lengths,
    reference_frame_lengths,
    sized_by_kind,
    sized_like,
)
from handdb.lengths.ratios import bone_ratios, joint_ratios, table1_measurements
from handdb.store.tables import empty, schema
from handdb.synthetic import synthesize_clip

#: Curl per frame (radians) of the short clip; frame 3 shows the flat, stretched hand.
CURL = np.array([0.9, 0.6, 0.3, 0.0, 0.4, 1.2])

#: A longer motion: the fingers curl and open again, the flat hand now and then.
LONG_CURL = np.abs(np.sin(np.linspace(0.0, 3.0 * np.pi, 90))) * 1.1


@pytest.fixture(scope="module")
def ratios():
    return joint_ratios(table1_measurements())


def relative_errors(result, truth, bones):
    return np.abs(result.lengths[bones] - truth[bones]) / truth[bones]


def test_one_known_length_gives_every_bone_from_the_whole_clip(make_clip, hand):
    clip = make_clip(LONG_CURL, bone_lengths={"index_pip": 49.0})
    truth = hand.true_lengths(clip.skeleton) * 49.0 / hand.true_lengths(clip.skeleton)[6]
    result = clip_bone_lengths(clip)
    assert result.sources[6] == "given" and result.lengths[6] == 49.0
    estimated = [j for j, s in enumerate(result.sources) if s == "clip"]
    assert len(estimated) == clip.skeleton.n_joints - 2
    assert relative_errors(result, truth, estimated).max() < 0.05
    assert np.all(result.uncertainty[estimated] > 0)
    assert np.isnan(result.uncertainty[6]) and np.isnan(result.lengths[clip.skeleton.root])


def test_the_whole_clip_beats_one_frame_assumed_flat():
    # hands of the population before a pinhole camera, with a tracker's pixel noise: no
    # frame is exactly flat and facing the camera, as in real clips
    errors = {"clip": [], "reference frame": []}
    for seed, motion in enumerate(["random", "wave", "random", "wave"]):
        synthetic = synthesize_clip(motion, 300, seed=seed, camera="pinhole", noise_px=1.0)
        clip = synthetic.as_clip("s")
        skeleton = clip.skeleton
        truth = np.array([synthetic.bone_lengths.get(j, np.nan) for j in skeleton.joints])
        known = {"index_pip": float(truth[skeleton.index("index_pip")])}
        clip = replace(clip, truth=None, spec=replace(clip.spec, bone_lengths=known))
        unknown = [j for j in skeleton.bones[:, 1] if skeleton.joints[j] not in known]
        lengths = clip_bone_lengths(clip).lengths
        given = np.array([known.get(j, np.nan) for j in skeleton.joints])
        reference = reference_frame_lengths(clip.uv, skeleton, given)
        errors["clip"].append(np.abs(lengths - truth)[unknown])
        errors["reference frame"].append(np.abs(reference - truth)[unknown])
    assert np.mean(errors["clip"]) < np.nanmean(errors["reference frame"])


def population_clip(seed, motion, hand_length_mm=None):
    """A hand of the population before a pinhole camera, with a tracker's pixel noise, its
    clip without truth or lengths and its true bone lengths ``(J,)``, mm."""
    synthetic = synthesize_clip(motion, 300, seed=seed, camera="pinhole", noise_px=1.0,
                                hand_length_mm=hand_length_mm)
    clip = synthetic.as_clip("s")
    clip = replace(clip, truth=None, spec=replace(clip.spec, bone_lengths={}))
    truth = np.array([synthetic.bone_lengths.get(j, np.nan) for j in clip.skeleton.joints])
    return clip, truth


@pytest.mark.parametrize("seed, motion, hand_length_mm",
                         [(0, "random", 165.0), (1, "wave", 200.0), (4, "clench", 170.0)])
def test_one_length_or_a_hand_length_gives_a_hand_of_the_right_size(seed, motion,
                                                                    hand_length_mm):
    clip, truth = population_clip(seed, motion, hand_length_mm)
    bones = clip.skeleton.bones[:, 1]
    one = {"middle_pip": float(truth[clip.skeleton.index("middle_pip")])}
    for spec in (replace(clip.spec, bone_lengths=one),
                 replace(clip.spec, hand_length=hand_length_mm)):
        ratio = clip_bone_lengths(replace(clip, spec=spec)).lengths[bones] / truth[bones]
        # the population's hands differ in length by 6 % (1 sd); these sizes do not
        assert abs(np.median(ratio) - 1.0) < 0.07
        assert np.std(np.log(ratio)) < 0.1


@pytest.mark.parametrize("seed, motion", [(1, "random"), (2, "clench")])
def test_a_held_pose_reports_an_uncertainty_that_covers_its_errors(seed, motion):
    # one pose held for the whole clip: the envelope is one view's foreshortened length,
    # which the images alone cannot tell from the bone's length; the envelopes then
    # disagree with the hand's proportions, and the uncertainty must say so (these clips
    # covered 11 % and 32 % of their errors at two standard deviations before it did)
    synthetic = synthesize_clip(motion, 120, seed=seed, camera="pinhole", noise_px=1.0)
    held = replace(synthetic, uv=np.repeat(synthetic.uv[60][None], 120, axis=0))
    clip = held.as_clip("s")
    skeleton = clip.skeleton
    truth = np.array([synthetic.bone_lengths.get(j, np.nan) for j in skeleton.joints])
    known = {"middle_pip": float(truth[skeleton.index("middle_pip")])}
    clip = replace(clip, truth=None, spec=replace(clip.spec, bone_lengths=known))
    result = clip_bone_lengths(clip)
    unknown = [j for j in skeleton.bones[:, 1] if skeleton.joints[j] not in known]
    error = np.abs(result.lengths - truth)[unknown]
    assert np.mean(error < 2.0 * result.uncertainty[unknown]) >= 0.85


def test_a_moving_hand_keeps_its_uncertainty():
    # evidence that agrees within its spreads is not widened
    clip, truth = population_clip(0, "random")
    skeleton = clip.skeleton
    known = {"middle_pip": float(truth[skeleton.index("middle_pip")])}
    result = clip_bone_lengths(replace(clip, spec=replace(clip.spec, bone_lengths=known)))
    unknown = [j for j in skeleton.bones[:, 1] if skeleton.joints[j] not in known]
    relative = result.uncertainty[unknown] / result.lengths[unknown]
    assert np.median(relative) < 0.08


def test_consistency_ratio_is_the_disagreement_beyond_the_spreads():
    bones = np.arange(1, 5)
    lengths = np.array([np.nan, 10.0, 20.0, 30.0, 40.0])
    spread = np.full(5, 0.05)
    frames = np.zeros(5, dtype=np.int64)
    a = Estimate(lengths, spread, frames)
    agreeing = Estimate(lengths * np.exp(0.05 * np.array([0, 1, -1, 1, -1])), spread, frames)
    assert consistency_ratio([a, agreeing], combine([a, agreeing]), bones) == 1.0
    # each pair 0.3 apart in log, 0.05 each: 0.15 from their mean, 3 spreads, chi2 18 per
    # bone on one degree of freedom
    apart = Estimate(lengths * np.exp(0.3), spread, frames)
    assert consistency_ratio([a, apart], combine([a, apart]), bones) == pytest.approx(
        np.sqrt(18.0))
    lone = Estimate(np.where(bones[0] == np.arange(5), 12.0, np.nan), spread, frames)
    assert consistency_ratio([a, lone], combine([a, lone]), bones[1:]) == 1.0


def test_without_a_length_every_bone_keeps_the_hand_lengths_spread(make_clip):
    # the population's hand length sizes the images and the proportions alike: its 6 %
    # is not averaged away by combining them
    result = clip_bone_lengths(make_clip(LONG_CURL))
    bones = result.skeleton.bones[:, 1]
    assert np.all(result.uncertainty[bones] / result.lengths[bones] >= 0.06)


def test_the_palm_is_sized_by_its_own_known_bones():
    # the palm's bones from the wrist fall shorter of their image envelopes than the
    # phalanges do: sized by the known middle metacarpal, not by one factor for all
    five = ("middle_mcp", "middle_pip", "middle_dip", "middle_tip", "thumb_cmc")
    errors = {"one factor": [], "by kind": []}
    for seed, motion in [(1, "wave"), (2, "random"), (3, "wave")]:
        clip, truth = population_clip(seed, motion)
        skeleton = clip.skeleton
        known = np.array([truth[j] if name in five else np.nan
                          for j, name in enumerate(skeleton.joints)])
        shape = image_proportions(clip.uv, skeleton, hand_proportions(skeleton))
        palm = palm_bones(skeleton) & np.isnan(known)
        one = sized_like(shape, Estimate(known, np.zeros_like(known), shape.n_frames))
        errors["one factor"].append(np.abs(one.lengths - truth)[palm])
        errors["by kind"].append(np.abs(sized_by_kind(shape, known, palm_bones(skeleton))
                                        .lengths - truth)[palm])
    assert np.mean(errors["by kind"]) < 0.5 * np.mean(errors["one factor"])


def test_palm_bones_are_the_wrist_to_the_long_fingers_and_palm_centre():
    for name, expected in [("mediapipe21", {"index_mcp", "middle_mcp", "ring_mcp",
                                            "little_mcp"}),
                           ("dhg22", {"palm", "index_mcp", "middle_mcp", "ring_mcp",
                                      "little_mcp"})]:
        skeleton = load_skeleton(name)
        assert {skeleton.joints[j] for j in np.flatnonzero(palm_bones(skeleton))} == expected


def test_a_clip_with_no_length_gets_an_average_hand_with_its_spread(make_clip, hand):
    clip = make_clip(LONG_CURL)
    result = clip_bone_lengths(clip)
    assert set(result.sources) - {None} <= {"clip", "population"}
    skeleton = clip.skeleton
    bones = skeleton.bones[:, 1]
    truth = hand.true_lengths(skeleton)
    # the hand's proportions come from the images, its size from the population (+-6 %)
    ratio = result.lengths[bones] / truth[bones]
    assert np.std(ratio) < 0.05 and abs(np.median(ratio) - 1.0) < 0.1
    assert np.all(result.uncertainty[bones] / result.lengths[bones] > 0.05)


def test_a_given_hand_length_sizes_the_hand(make_clip, hand, tmp_path):
    clip = make_clip(LONG_CURL)
    spec = replace(clip.spec, hand_length=2.0 * hand.hand_length_mm)
    result = clip_bone_lengths(replace(clip, spec=spec))
    skeleton = clip.skeleton
    ratio = result.lengths[skeleton.bones[:, 1]] / hand.true_lengths(skeleton)[skeleton.bones[:, 1]]
    assert np.median(ratio) == pytest.approx(2.0, rel=0.08)


def test_truth_beats_estimates_and_given_beats_truth(make_clip, hand):
    clip = make_clip(CURL, bone_lengths={"thumb_tip": 20.0}, with_truth=True)
    result = clip_bone_lengths(clip)
    truth = hand.true_lengths(clip.skeleton)
    assert set(result.sources) - {None} == {"given", "truth"}
    assert result.lengths[clip.skeleton.index("thumb_tip")] == 20.0
    measured = [j for j, s in enumerate(result.sources) if s == "truth"]
    np.testing.assert_allclose(result.lengths[measured], truth[measured])
    assert (result.n_frames[measured] == CURL.size).all()


def test_a_finger_never_seen_takes_the_xray_shares_of_its_seen_phalanges(make_clip, ratios):
    hidden = ("ring_dip", "ring_tip")
    clip = make_clip(LONG_CURL, bone_lengths={"index_pip": 49.0}, hidden=hidden)
    result = clip_bone_lengths(clip, ratios)
    skeleton = clip.skeleton
    for joint in hidden:
        assert result.sources[skeleton.index(joint)] == "ratios"
    mean, _ = bone_ratios(skeleton, ratios)
    pip, dip = skeleton.index("ring_pip"), skeleton.index("ring_dip")
    expected = result.lengths[pip] / mean[pip] * mean[dip]
    assert result.lengths[dip] == pytest.approx(expected, rel=0.1)


def test_a_palm_bone_never_seen_comes_from_the_hands_proportions(make_clip):
    clip = make_clip(LONG_CURL, bone_lengths={"index_pip": 49.0}, hidden=("little_mcp",))
    result = clip_bone_lengths(clip)
    little = clip.skeleton.index("little_mcp")
    assert result.sources[little] == "proportions"
    assert "hand" in result.details[little]


def test_ratio_lengths_average_the_other_known_phalanges(ratios):
    skeleton = load_skeleton("mediapipe21")
    mean, _ = bone_ratios(skeleton, ratios)
    known = np.full(skeleton.n_joints, np.nan)
    pip, dip, tip = skeleton.indices(["middle_pip", "middle_dip", "middle_tip"])
    known[pip], known[dip] = 50.0, 30.0
    estimate = ratio_lengths(skeleton, known, mean)
    total = (50.0 / mean[pip] + 30.0 / mean[dip]) / 2
    assert estimate.lengths[tip] == pytest.approx(total * mean[tip])
    assert estimate.lengths[pip] == pytest.approx(30.0 / mean[dip] * mean[pip])
    assert np.isnan(estimate.lengths[skeleton.index("index_tip")])


def test_table_has_a_row_per_bone_with_its_uncertainty(make_clip):
    clip = make_clip(LONG_CURL, bone_lengths={"index_pip": 49.0})
    result = clip_bone_lengths(clip)
    table = bone_lengths_table(clip.clip_id, "s01", clip.skeleton, result)
    assert table.schema.equals(schema("bone_lengths"), check_metadata=False)
    assert table.num_rows == len(clip.skeleton.bone_names)
    assert set(table["source"].to_pylist()) <= set(SOURCES)
    given = table.filter(pc.equal(table["source"], "given"))
    assert given["uncertainty"].null_count == 1 and given["units"][0].as_py() == "mm"
    assert table.filter(pc.equal(table["source"], "clip"))["uncertainty"].null_count == 0


def test_the_middle_finger_spans_the_hand():
    proportions = hand_length_proportions(load_skeleton("mediapipe21"))
    chain = load_skeleton("mediapipe21").finger_chain("middle")
    assert proportions[chain].sum() == pytest.approx(1.0)


def test_empty_ratio_table_falls_back_to_table1(make_clip):
    clip = make_clip(LONG_CURL, bone_lengths={"index_pip": 49.0}, hidden=("ring_tip",))
    result = clip_bone_lengths(clip, empty("joint_ratios"))
    assert result.sources[clip.skeleton.index("ring_tip")] == "ratios"
    assert result.lengths == pytest.approx(clip_bone_lengths(clip).lengths, nan_ok=True)


def test_a_sidecar_hand_length_must_be_a_positive_number(tmp_path):
    from handdb.errors import InputError
    from handdb.ingest.sidecar import parse_sidecar

    sidecar = tmp_path / "c.clip.json"
    sidecar.write_text(json.dumps({"skeleton": "mediapipe21", "hand": "right", "fps": 30,
                                   "subject": "s", "units": "mm",
                                   "camera": {"model": "orthographic"}, "hand_length": -3}))
    with pytest.raises(InputError, match="hand_length"):
        parse_sidecar(sidecar)
