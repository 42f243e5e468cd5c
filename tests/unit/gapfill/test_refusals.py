"""What gap filling does with what detectors drop (issue 15): a joint never observed is
placed by the hand model, frames observing nothing are bridged when short and interior and
kept unfilled otherwise, and only a clip that never shows enough of the palm is refused.

Real labelled frames sparse in time (DeepLabCut's labelled images at their image numbers)
crashed ``auto`` with numpy's ``LinAlgError: Singular matrix`` in the regression."""

import json
import re
import shutil

import numpy as np
import pytest

from handdb.clip import IMAGES
from handdb.errors import ClipDataError, GapFillError, ParameterError
from handdb.gapfill import UNFILLED, WHOLE_CLIP, fill_gaps
from handdb.gapfill.auto import SHORT_GAP
from handdb.ingest import discover, load_clip

#: The body parts of the DeepLabCut hands project, as canonical joints: no thumb_cmc, no
#: finger dip.
BRICE_MAP = {"wristCenter": "wrist", "thumbStart": "thumb_mcp", "thumbCenter": "thumb_ip",
             "thumbEnd": "thumb_tip"} | {
    f"{finger}{part}": f"{finger}_{joint}" for finger in ("index", "middle", "ring", "little")
    for part, joint in (("Start", "mcp"), ("Center", "pip"), ("End", "tip"))}
DLC = "dlc-hands/CollectedData_Brice.csv"


def _hidden_joint_and_empty_frames(clip, skeleton, empty):
    observed = np.ones(clip.uv.shape[:2], dtype=bool)
    observed[:, skeleton.index("thumb_cmc")] = False
    observed[empty] = False
    return observed


def test_a_never_seen_joint_is_placed_across_a_short_run_of_empty_frames(rapid_clip,
                                                                         mediapipe):
    observed = _hidden_joint_and_empty_frames(rapid_clip, mediapipe, slice(100, 105))
    result = fill_gaps(rapid_clip.uv, observed, mediapipe, "auto")
    assert np.isfinite(result.uv).all() and result.filled[100:105].all()
    assert np.isin(result.fill_method[:, mediapipe.index("thumb_cmc")],
                   ["chord", "rest-pose"]).all()
    assert [f.joint for f in result.flags if f.kind == WHOLE_CLIP] == ["thumb_cmc"]
    np.testing.assert_array_equal(result.uv[observed], rapid_clip.uv[observed])
    hand_px = np.ptp(rapid_clip.uv[100], axis=0).max()
    bridged = np.linalg.norm(result.uv[100:105] - rapid_clip.uv[100:105], axis=-1)
    assert np.median(bridged) < 0.1 * hand_px


@pytest.mark.parametrize("empty", [slice(0, 3), slice(100, 100 + SHORT_GAP + 1),
                                   slice(395, 400)])
def test_empty_frames_at_the_ends_or_in_long_runs_stay_unfilled(rapid_clip, mediapipe, empty):
    observed = _hidden_joint_and_empty_frames(rapid_clip, mediapipe, empty)
    result = fill_gaps(rapid_clip.uv, observed, mediapipe, "auto")
    kept = np.zeros(len(observed), dtype=bool)
    kept[empty] = True
    assert np.isnan(result.uv[kept]).all() and not result.filled[kept].any()
    assert np.isfinite(result.uv[~kept]).all()
    unfilled = {(f.start, f.stop) for f in result.flags if f.kind == UNFILLED}
    assert unfilled == {(empty.start, empty.stop)}


def test_a_clip_that_never_observes_enough_of_the_palm_is_refused(rapid_clip, mediapipe):
    observed = np.zeros(rapid_clip.uv.shape[:2], dtype=bool)
    for joint in ("wrist", "index_mcp", "index_pip", "index_dip", "index_tip"):
        observed[:, mediapipe.index(joint)] = True
    with pytest.raises(GapFillError) as info:
        fill_gaps(rapid_clip.uv, observed, mediapipe, "auto")
    message = str(info.value)
    assert isinstance(info.value, ClipDataError)
    for part in ("'auto' cannot place thumb_cmc", "no frame observes 3", "wrist, index_mcp)",
                 '"joint_map"', '"gap_fill": {"method": "rigid"}'):
        assert part in message


@pytest.mark.parametrize(("never_seen", "empty"), [("thumb_cmc", slice(0, 0)),
                                                   (None, slice(100, 105))])
def test_a_never_seen_joint_or_an_empty_run_alone_is_filled(rapid_clip, mediapipe,
                                                            never_seen, empty):
    observed = np.ones(rapid_clip.uv.shape[:2], dtype=bool)
    observed[empty] = False
    if never_seen:
        observed[:, mediapipe.index(never_seen)] = False
    filled = fill_gaps(rapid_clip.uv, observed, mediapipe, "auto").uv
    assert np.isfinite(filled).all()


def test_rigid_fills_the_refused_clip_and_flags_what_it_cannot_place(rapid_clip, mediapipe):
    observed = _hidden_joint_and_empty_frames(rapid_clip, mediapipe, slice(100, 105))
    result = fill_gaps(rapid_clip.uv, observed, mediapipe, "rigid")
    unfilled = [f for f in result.flags if f.kind == UNFILLED]
    assert {(f.joint, f.start, f.stop) for f in unfilled} == {("thumb_cmc", 100, 105)}


def test_an_unknown_long_gap_rule_is_a_parameter_error(rapid_clip, mediapipe):
    observed = np.ones(rapid_clip.uv.shape[:2], dtype=bool)
    observed[50:80, mediapipe.index("index_tip")] = False
    with pytest.raises(ParameterError, match="long_gaps must be one of"):
        fill_gaps(rapid_clip.uv, observed, mediapipe, "auto", long_gaps="spline")


def _dlc_hand(real_tools, tmp_path, individual):
    """The DeepLabCut file's labelled images of one hand, by row, and their image numbers."""
    shutil.copy(real_tools / DLC, tmp_path / "clip.dlc.csv")
    (tmp_path / "clip.clip.json").write_text(json.dumps({
        "skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
        "units": "mm", "camera": {"model": "orthographic"}, "individual": individual,
        "frame_from": "row", "joint_map": BRICE_MAP}))
    (entry,) = discover(tmp_path).clips
    clip = load_clip(entry)
    images = [line.split(",", 1)[0] for line in (real_tools / DLC).read_text().splitlines()[4:]]
    numbers = np.array([int(re.search(r"(\d+)\D*$", image).group(1)) for image in images])
    return clip, numbers


@pytest.mark.parametrize("individual", ["leftHand", "rightHand"])
def test_real_labelled_frames_sparse_in_time_are_filled_alone(real_tools, tmp_path, individual):
    """Labelled images at their image numbers: runs of more than ``SHORT_GAP`` frames
    between them stay unfilled, the shorter ones are bridged."""
    clip, numbers = _dlc_hand(real_tools, tmp_path, individual)
    uv = np.full((numbers.max() + 1, *clip.uv.shape[1:]), np.nan)
    uv[numbers] = clip.uv
    observed = np.isfinite(uv).all(axis=-1)
    assert observed.any(axis=1).sum() == len(numbers) < len(uv) / 20
    result = fill_gaps(uv, observed, clip.skeleton, "auto")
    between = np.diff(np.sort(numbers)) - 1
    bridged = np.zeros(len(uv), dtype=bool)
    for first, run in zip(np.sort(numbers)[:-1] + 1, between, strict=True):
        bridged[first:first + run] = run <= SHORT_GAP
    bridged[numbers] = True
    assert 0 < (bridged.sum() - len(numbers)) and (~bridged).sum() > len(uv) / 2
    assert np.isfinite(result.uv[bridged]).all()
    assert np.isnan(result.uv[~bridged]).all()


@pytest.mark.parametrize("individual", ["leftHand", "rightHand"])
def test_real_labelled_frames_in_row_order_are_filled(real_tools, tmp_path, individual):
    clip, _ = _dlc_hand(real_tools, tmp_path, individual)
    observed = np.isfinite(clip.uv).all(axis=-1)
    filled = fill_gaps(clip.uv, observed, clip.skeleton, "auto").uv
    assert np.isfinite(filled).all()
    np.testing.assert_array_equal(filled[observed], clip.uv[observed])


def test_a_joint_an_annotation_skips_is_placed_on_the_chord_of_its_neighbours(rapid_clip,
                                                                           mediapipe):
    dip, pip, tip = (mediapipe.index(f"index_{role}") for role in ("dip", "pip", "tip"))
    observed = np.ones(rapid_clip.uv.shape[:2], dtype=bool)
    observed[:, dip] = False
    result = fill_gaps(rapid_clip.uv, observed, mediapipe, "auto")
    assert (result.fill_method[:, dip] == "chord").all()
    chord = rapid_clip.uv[:, tip] - rapid_clip.uv[:, pip]
    offset = result.uv[:, dip] - rapid_clip.uv[:, pip]
    share = np.sum(offset * chord, axis=-1) / np.sum(chord * chord, axis=-1)
    across = np.abs(np.cross(chord, offset)) / np.linalg.norm(chord, axis=-1)
    assert np.all((share > 0.3) & (share < 0.7))
    assert np.all(across < 1e-6 * np.linalg.norm(chord, axis=-1))


def test_an_image_that_shows_too_little_of_the_palm_is_left_alone(rapid_clip, mediapipe):
    """Independent images: one without a palm stays unfilled, the others are filled; only a
    set of which no image shows the palm is refused."""
    images = rapid_clip.uv[:6]
    observed = np.ones(images.shape[:2], dtype=bool)
    observed[:, mediapipe.index("thumb_cmc")] = False
    fingertips = [mediapipe.index(f"{finger}_tip") for finger in ("index", "middle", "ring")]
    observed[2] = False
    observed[2, fingertips] = True
    result = fill_gaps(images, observed, mediapipe, "auto", sampling=IMAGES)
    others = np.arange(6) != 2
    assert np.isfinite(result.uv[others]).all() and not result.filled[2].any()
    palmless = np.zeros_like(observed)
    palmless[:, fingertips] = True
    with pytest.raises(GapFillError, match="no frame observes 3 of those"):
        fill_gaps(images, palmless, mediapipe, "auto", sampling=IMAGES)
