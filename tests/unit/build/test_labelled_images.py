"""DeepLabCut labelled data is a set of independent images, not a track (issue 15).

The 20 labelled hands of the real DeepLabCut project were built as one continuous clip:
gap filling smoothed across unrelated images and the lifting's temporal model tied their
depth signs, and both hands came out flagged (fingers bent beyond their range in 20 % and
70 % of the frames). Read in row order, labelled images are now a clip of ``"images"``
sampling: each is filled and lifted on its own, so an image's result does not depend on
its neighbours.
"""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from handdb.build import BuildOptions, build_in_process
from handdb.cli import lift as lift_command
from handdb.clip import IMAGES, VIDEO
from handdb.gapfill import fill_gaps
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.ingest import discover, dlc, get_format, load_clip
from handdb.lifting import lift
from handdb.store.query import query
from handdb.synthetic.clips import synthesize_clip
from tests.support.real_tools import BRICE_MAP, SIDECAR_2D, put

#: Images picked from a synthetic clip, in the order a labeller might list them.
N_IMAGES, SEED = 16, 4
DIPS = ("index_dip", "middle_dip", "ring_dip", "little_dip")
#: The lifting methods ``handdb lift compare`` is run with here.
FAST_METHODS = ("kinematic", "kinematic-refined", "thesis")


@pytest.fixture(scope="module")
def labelled():
    """Labelled images of a synthetic hand (no DIP labelled), unordered in time."""
    clip = synthesize_clip("random", 120, seed=SEED)
    picked = np.random.default_rng(SEED).choice(clip.n_frames, N_IMAGES, replace=False)
    skeleton = load_skeleton(clip.skeleton)
    uv = clip.uv[picked].copy()
    uv[:, skeleton.indices(list(DIPS))] = np.nan
    return clip, picked, uv


def write_labelled_csv(path, uv, picked, index="image"):
    """A DeepLabCut labelled-data CSV: image paths in the first column."""
    skeleton = load_skeleton("mediapipe21")
    dlc.write(path, uv, None, skeleton, scorer="labeller")
    lines = path.read_text().splitlines()
    for k, frame in enumerate(picked):
        cell = f"labeled-data\\video1\\img{frame:03d}.png" if index == "image" else str(k)
        lines[3 + k] = cell + lines[3 + k][lines[3 + k].index(","):]
    path.write_text("\n".join(lines) + "\n")


def inbox_with(folder, clip, uv, picked, **sidecar):
    folder.mkdir(parents=True)
    write_labelled_csv(folder / "hand.dlc.csv", uv, picked)
    (folder / "hand.clip.json").write_text(json.dumps(
        clip.sidecar() | {"frame_from": "row"} | sidecar))
    return folder


@pytest.mark.parametrize(("index", "frame_from", "sampling"), [
    ("image", "row", IMAGES), ("image", "image_name", VIDEO), ("frame", "row", VIDEO),
    ("frame", None, VIDEO)])
def test_only_labelled_images_read_by_row_are_independent(tmp_path, labelled, index,
                                                          frame_from, sampling):
    clip, _, uv = labelled
    # every other frame of a video: dense enough to be placed in it as a track with gaps
    numbers = 2 * np.arange(N_IMAGES)
    write_labelled_csv(tmp_path / "hand.dlc.csv", uv, numbers, index)
    keys = {"frame_from": frame_from} if frame_from else {}
    (tmp_path / "hand.clip.json").write_text(json.dumps(clip.sidecar() | keys))
    (entry,) = discover(tmp_path).clips
    read = load_clip(entry)
    assert read.sampling == sampling
    assert read.n_frames == (2 * N_IMAGES - 1 if frame_from == "image_name" else N_IMAGES)


def test_each_image_is_filled_and_lifted_on_its_own(labelled):
    clip, _, uv = labelled
    skeleton = load_skeleton(clip.skeleton)
    observed = np.isfinite(uv).all(axis=-1)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    camera = synthesize_clip("random", 2, seed=SEED).as_clip().spec.camera
    filled = fill_gaps(uv, observed, skeleton, sampling=IMAGES).uv
    joined = lift(filled, skeleton, lengths, camera, sampling=IMAGES)
    odds = []
    for k in range(N_IMAGES):
        alone = fill_gaps(uv[k:k + 1], observed[k:k + 1], skeleton).uv
        np.testing.assert_array_equal(filled[k:k + 1], alone)
        image = lift(alone, skeleton, lengths, camera)
        np.testing.assert_array_equal(joined.xyz[k:k + 1], image.xyz)
        odds.append(image.mirror_log_odds)
    assert joined.mirror_log_odds == min(odds), "the least settled image's odds"
    as_track = fill_gaps(uv, observed, skeleton).uv
    assert not np.allclose(as_track, filled), "a track is filled across frames"
    with pytest.raises(ValueError, match="sampling must be one of video, images"):
        lift(filled, skeleton, lengths, camera, sampling="film")


def test_labelled_images_build_the_same_in_any_order(tmp_path, labelled):
    clip, picked, uv = labelled
    reverse = slice(None, None, -1)
    xyz = {}
    for name, order in (("listed", slice(None)), ("reversed", reverse)):
        inbox = inbox_with(tmp_path / name / "inbox", clip, uv[order], picked[order])
        db = str(tmp_path / name / "db")
        summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
        assert list(summary.processed) == ["hand"]
        row = query(db, "SELECT sampling, flag_reasons FROM clips").to_pylist()[0]
        assert row == {"sampling": IMAGES, "flag_reasons": [
            f"{dip} never detected: placed by the hand model (chord)" for dip in DIPS]}
        joints = query(db, "SELECT frame, joint_index, x, y, z FROM joints_3d "
                           "ORDER BY frame, joint_index").to_pydict()
        xyz[name] = np.stack([joints[c] for c in "xyz"], axis=-1).reshape(N_IMAGES, -1, 3)
    np.testing.assert_allclose(xyz["reversed"][reverse], xyz["listed"], atol=1e-9)


@pytest.mark.parametrize(("individual", "hand"), [("leftHand", "left"),
                                                  ("rightHand", "right")])
def test_the_real_labelled_hands_build_plausible(real_tools, tmp_path, individual, hand):
    put(real_tools, tmp_path / "inbox", "dlc", SIDECAR_2D | {
        "hand": hand, "individual": individual, "frame_from": "row", "joint_map": BRICE_MAP,
        "bone_lengths": {"index_pip": 40.0}, "image": {"width": 852, "height": 480}})
    db = str(tmp_path / "db")
    summary = build_in_process(tmp_path / "inbox", db, BuildOptions(export_usd=False))
    assert list(summary.processed) == ["clip"] and not summary.refusals
    (row,) = query(db, "SELECT n_frames, sampling, flag_reasons FROM clips").to_pylist()
    assert (row["n_frames"], row["sampling"]) == (20, IMAGES)
    # the annotation has no thumb_cmc and no DIP: said, and nothing implausible besides
    assert [reason.split(" never detected: placed by the hand model")[0]
            for reason in row["flag_reasons"]] == ["thumb_cmc", *DIPS]
    placed = query(db, "SELECT count(*) AS n FROM joints_3d WHERE isfinite(z)").to_pylist()
    assert placed == [{"n": 20 * 21}]


def test_lift_compare_fills_and_lifts_each_labelled_image_on_its_own(tmp_path, labelled,
                                                                     monkeypatch):
    """As the build does: the comparison of an inbox's labelled images is the same in any
    order of the images (each image's depth is its own, never tied to the next one's)."""
    # the model fit takes seconds per image; the fast methods show the sampling is kept
    monkeypatch.setattr(lift_command, "available_methods", lambda: FAST_METHODS)
    clip, picked, uv = labelled
    skeleton = load_skeleton(clip.skeleton)
    printed = {}
    for name, order in (("listed", slice(None)), ("reversed", slice(None, None, -1))):
        inbox = inbox_with(tmp_path / name, clip, uv[order], picked[order])
        get_format("truth_csv").write(inbox / "hand.truth.csv", clip.xyz[picked[order]],
                                      skeleton)
        result = CliRunner().invoke(lift_command.app, ["compare", "--inbox", str(inbox),
                                                       "--clip", "hand"], terminal_width=200)
        assert result.exit_code == 0, result.output
        printed[name] = result.output
    assert "hand: depth against ground truth" in printed["listed"]
    assert printed["reversed"] == printed["listed"]
