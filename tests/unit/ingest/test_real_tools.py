"""The real files of ../shared/data/real-tools: each is read into a clip or refused with a
message that says what to do (issue 15). Files are copied into a temporary inbox."""

import json
import re
import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import discover, load_clip
from tests.support.real_tools import (
    BRICE_MAP,
    GLOVE_MARKERS,
    GLOVE_TIPS,
    SIDECAR_2D,
    SIDECAR_3D,
    SOURCES,
    put,
)


def read(inbox):
    scan = discover(inbox)
    assert scan.refused == ()
    (entry,) = scan.clips
    return load_clip(entry)


def refusal(inbox):
    scan = discover(inbox)
    assert scan.refused == ()
    with pytest.raises(InputError) as info:
        load_clip(scan.clips[0])
    return info.value


def points(clip):
    data = clip.markers if clip.markers is not None else clip.uv
    return np.isfinite(data).all(axis=-1)


# --- accepted as the tools wrote them -------------------------------------------------------

@pytest.mark.parametrize(("hand", "observed", "wrist"), [("right", 169, [530.9, 463.3]),
                                                         ("left", 189, [740.3, 521.2])])
def test_openpose_hand_json(real_tools, tmp_path, hand, observed, wrist):
    put(real_tools, tmp_path, "openpose", SIDECAR_2D | {"hand": hand, "person": 0})
    clip = read(tmp_path)
    assert (clip.n_frames, points(clip).sum(), clip.observed.sum()) == (9, 189, observed)
    np.testing.assert_allclose(clip.uv[0, 0], wrist, atol=0.1)


#: An image size that holds the real OpenPose sample's keypoints, pixels.
OPENPOSE_IMAGE = (1280, 720)


def rescaled_openpose(real_tools, folder, to_unit):
    """The real OpenPose sample with every 2D keypoint's x, y mapped by ``to_unit(xy)``,
    as OpenPose's ``--keypoint_scale`` writes them (points 0, 0, 0 stay missing)."""
    folder.mkdir(parents=True)
    size = np.asarray(OPENPOSE_IMAGE, dtype=np.float64)
    for path in sorted((real_tools / SOURCES["openpose"][0]).iterdir()):
        doc = json.loads(path.read_text())
        for person in doc["people"]:
            for key, values in person.items():
                if key.endswith("_keypoints_2d") and values:
                    points = np.asarray(values, dtype=np.float64).reshape(-1, 3)
                    seen = points.any(axis=1)
                    points[seen, :2] = to_unit(points[seen, :2] / size)
                    person[key] = points.ravel().tolist()
        (folder / path.name).write_text(json.dumps(doc))


@pytest.mark.parametrize(("coordinates", "to_unit"), [("normalized", lambda xy: xy),
                                                      ("normalized_signed",
                                                       lambda xy: 2.0 * xy - 1.0)])
def test_openpose_keypoint_scale_is_refused_as_pixels_and_read_when_said(
        real_tools, tmp_path, coordinates, to_unit):
    """``--keypoint_scale 3`` ([0, 1]) and ``4`` ([-1, 1]) output of the real sample:
    refused where the sidecar says nothing (the keypoint file and field named, the
    sidecar keys to add), read as the original once it says so."""
    sidecar = SIDECAR_2D | {"hand": "left", "person": 0}
    put(real_tools, tmp_path / "pixels", "openpose", sidecar)
    (tmp_path / "scaled").mkdir()
    rescaled_openpose(real_tools, tmp_path / "scaled" / "clip.openpose", to_unit)
    (tmp_path / "scaled" / "clip.clip.json").write_text(json.dumps(sidecar))
    error = refusal(tmp_path / "scaled")
    assert re.fullmatch(r"video_0000000000\d\d_keypoints\.json", Path(error.file).name)
    assert re.fullmatch(r"people\[0\]\.hand_left_keypoints_2d\[\w+\]\.[xy]", error.field)
    for phrase in ("normalised to the image", "--keypoint_scale 3 or 4",
                   '"coordinates": "normalized"', '"normalized_signed"'):
        assert phrase in error.reason
    width, height = OPENPOSE_IMAGE
    (tmp_path / "scaled" / "clip.clip.json").write_text(json.dumps(sidecar | {
        "coordinates": coordinates, "image": {"width": width, "height": height}}))
    np.testing.assert_allclose(read(tmp_path / "scaled").uv, read(tmp_path / "pixels").uv,
                               atol=1e-9)


@pytest.mark.parametrize("individual", ["leftHand", "rightHand"])
def test_dlc_multi_animal_labelled_data_by_row(real_tools, tmp_path, individual):
    put(real_tools, tmp_path, "dlc", SIDECAR_2D | {
        "individual": individual, "frame_from": "row", "joint_map": BRICE_MAP})
    clip = read(tmp_path)
    assert (clip.n_frames, points(clip).sum()) == (20, 320)
    assert np.isnan(clip.confidence).all(), "labelled data has no likelihood"
    assert not points(clip)[:, clip.skeleton.index("thumb_cmc")].any()


def test_dlc_23_split_index_columns_read_the_same(real_tools, tmp_path):
    sidecar = SIDECAR_2D | {"individual": "leftHand", "frame_from": "row",
                            "joint_map": BRICE_MAP}
    put(real_tools, tmp_path / "one", "dlc", sidecar)
    lines = (real_tools / SOURCES["dlc"][0]).read_text().splitlines()
    split = [line.replace(",", ",,,", 1) if k < 4 else line.replace("\\", ",", 2)
             for k, line in enumerate(lines)]
    (tmp_path / "three").mkdir()
    (tmp_path / "three" / "clip.dlc.csv").write_text("\n".join(split) + "\n")
    (tmp_path / "three" / "clip.clip.json").write_text(json.dumps(sidecar))
    assert split[4].startswith("labeled-data,Pil01,img040.png,")
    np.testing.assert_array_equal(read(tmp_path / "three").uv, read(tmp_path / "one").uv)


@pytest.mark.parametrize(("hand_index", "wrist_x"), [(0, 0.3068), (1, 0.7494)])
def test_mediapipe_long_csv(real_tools, tmp_path, hand_index, wrist_x):
    put(real_tools, tmp_path, "mediapipe", SIDECAR_2D | {
        "hand_index": hand_index, "image": {"width": 1280, "height": 720}})
    clip = read(tmp_path)
    assert (clip.n_frames, points(clip).sum()) == (64, 1344)
    assert clip.uv[0, 0, 0] == pytest.approx(wrist_x * 1280, abs=1.0)


def test_mediapipe_long_csv_as_tasks_json_reads_the_same(real_tools, tmp_path):
    """The same landmarks saved as MediaPipe Tasks results, one per frame."""
    rows = [line.split(",") for line in
            (real_tools / SOURCES["mediapipe"][0]).read_text().splitlines()[1:]]
    frames = []
    for frame in range(64):
        hands = [[{"x": float(r[3]), "y": float(r[4]), "z": float(r[5]), "visibility": 0.0,
                   "presence": 0.0} for r in rows if int(r[0]) == frame and int(r[1]) == k]
                 for k in (0, 1)]
        frames.append({"timestamp_ms": round(frame * 1000 / 30), "hand_landmarks": hands,
                       "handedness": [[{"index": 1, "score": 0.9, "category_name": "Left"}],
                                      [{"index": 0, "score": 0.8, "category_name": "Right"}]]})
    image = {"image": {"width": 1280, "height": 720}}
    put(real_tools, tmp_path / "csv", "mediapipe", SIDECAR_2D | image | {"hand_index": 1})
    (tmp_path / "json").mkdir()
    (tmp_path / "json" / "clip.mediapipe.json").write_text(json.dumps({"frames": frames}))
    (tmp_path / "json" / "clip.clip.json").write_text(
        json.dumps(SIDECAR_2D | image | {"handedness": "Right"}))
    from_json, from_csv = read(tmp_path / "json"), read(tmp_path / "csv")
    np.testing.assert_allclose(from_json.uv, from_csv.uv)
    np.testing.assert_array_equal(from_json.confidence, 0.8)


@pytest.mark.parametrize(("pixels_per_unit", "width", "axis"), [
    ((1280, 720), 1280, "x"), ((1280, 720), 1, "x"), ((1, 720), 1280, "y")])
def test_mediapipe_json_in_pixels_said_normalised_is_refused_on_either_axis(
        real_tools, tmp_path, pixels_per_unit, width, axis):
    """The real landmarks of hand 0 saved in pixels (on both axes, or on y only), the
    document saying nothing (so normalised, MediaPipe's own). An image one pixel wide
    scales x by 1: the check follows the coordinate system, not the scale, and names the
    landmark and the axis beyond the image."""
    rows = np.loadtxt(real_tools / SOURCES["mediapipe"][0], delimiter=",", skiprows=1)
    hand = rows[rows[:, 1] == 0]
    frames = [{"frame": int(frame), "landmarks": (hand[hand[:, 0] == frame][:, 3:6]
                                                 * [*pixels_per_unit, 1]).tolist()}
              for frame in np.unique(hand[:, 0])]
    (tmp_path / "clip.mediapipe.json").write_text(json.dumps({"frames": frames}))
    (tmp_path / "clip.clip.json").write_text(json.dumps(SIDECAR_2D | {
        "image": {"width": width, "height": 720}}))
    error = refusal(tmp_path)
    assert Path(error.file).name == "clip.mediapipe.json"
    assert re.fullmatch(r"frames\[0\]\.landmarks\[\d+\]", error.field), error.field
    assert f"at {axis}=" in error.reason and '"coordinates": "pixels"' in error.reason


@pytest.mark.parametrize("joint_map", [GLOVE_TIPS | dict.fromkeys(
    set(GLOVE_MARKERS) - set(GLOVE_TIPS)), GLOVE_TIPS | {"*": None}])
def test_qualisys_glove_tsv(real_tools, tmp_path, joint_map):
    put(real_tools, tmp_path, "qtm", SIDECAR_3D | {"fps": 100, "joint_map": joint_map})
    clip = read(tmp_path)
    seen = points(clip)
    assert clip.n_frames == 6000 and clip.source_format == "qtm"
    assert [clip.skeleton.joints[j] for j in np.flatnonzero(seen.any(axis=0))] == [
        "thumb_tip", "index_tip", "middle_tip", "ring_tip", "little_tip"]
    thumb = clip.skeleton.index("thumb_tip")
    assert (~seen[:, thumb]).sum() == 493 and not seen[885:907, thumb].any()
    np.testing.assert_allclose(clip.markers[0, thumb], [141.316, 248.687, 391.455])


@pytest.mark.parametrize(("capture", "hand"), [("3", "right"), ("3", "left"), (7, "left"),
                                               ("4", "right")])
def test_interhand_joint_3d(real_tools, tmp_path, capture, hand):
    put(real_tools, tmp_path, "interhand", SIDECAR_3D | {
        "hand": hand, "capture": capture, "frame_offset": "first", "units": "cm"})
    clip = read(tmp_path)
    assert clip.n_frames == 1 and points(clip).sum() == 21
    wrist, cmc = clip.markers[0, 0], clip.markers[0, clip.skeleton.index("thumb_cmc")]
    assert 2.5 < np.linalg.norm(cmc - wrist) < 5.0, "thumb CMC about 34 mm from the wrist"


def test_dhg_skeleton_file(dhg_sample, dhg_world, tmp_path):
    shutil.copy(dhg_sample, tmp_path / "gesture.dhg.txt")
    (tmp_path / "gesture.clip.json").write_text(json.dumps(SIDECAR_3D | {"skeleton": "dhg22"}))
    clip = read(tmp_path)
    assert clip.source_format == "dhg" and clip.markers.shape == (95, 22, 3)
    np.testing.assert_allclose(clip.markers, dhg_world * 1000.0)
    (tmp_path / "gesture.clip.json").write_text(json.dumps(SIDECAR_3D))
    assert read(tmp_path).markers.shape == (95, 21, 3), "the palm centre is dropped"


def honest_optotrak(real_tools, path, n_frames=29):
    """The Optotrak file with its header's frame count made that of its data."""
    data = bytearray((real_tools / SOURCES["optotrak"][0]).read_bytes())
    data[8:10] = struct.pack("<H", n_frames)
    at = data.find(b"FRAMES") + len("FRAMES") + 4
    data[at:at + 2] = struct.pack("<h", n_frames)
    path.write_bytes(bytes(data))


def test_optotrak_units_per_point_once_its_frame_count_is_true(real_tools, tmp_path):
    sidecar = SIDECAR_3D | {"units": "m", "joint_map": {"Marker_1": "wrist", "*": None}}
    put(real_tools, tmp_path, "optotrak", sidecar)
    honest_optotrak(real_tools, tmp_path / "clip.c3d")
    clip = read(tmp_path)
    assert clip.n_frames == 29 and points(clip)[:, 0].all() and points(clip).sum() == 29
    assert np.abs(clip.markers[:, 0]).max() < 1.5, "millimetres read as metres / 1000"


# --- refused, saying what to do --------------------------------------------------------------

def check(error, file, line, field, *phrases):
    assert (error.file.rsplit("/", 1)[-1], error.line, error.field) == (file, line, field)
    for phrase in phrases:
        assert phrase in error.reason, error.reason


def test_optotrak_as_shipped_is_truncated(real_tools, tmp_path):
    put(real_tools, tmp_path, "optotrak", SIDECAR_3D | {"joint_map": {"Marker_1": "wrist",
                                                                     "*": None}})
    check(refusal(tmp_path), "clip.c3d", None, "POINT:FRAMES",
          "holds 29 frames of POINT data, but its header says 1149",
          "(the file is 28640 bytes, 996320 needed)", "export it again")


def test_optotrak_extra_markers_need_the_joint_map(real_tools, tmp_path):
    put(real_tools, tmp_path, "optotrak", SIDECAR_3D | {"joint_map": {"Marker_1": "wrist"}})
    honest_optotrak(real_tools, tmp_path / "clip.c3d")
    check(refusal(tmp_path), "clip.c3d", None, "POINT:LABELS", "unknown joint 'Marker_2'",
          '"*": null')


def test_kistler_force_plates_have_no_points(real_tools, tmp_path):
    put(real_tools, tmp_path, "kistler", SIDECAR_3D | {"fps": 60})
    check(refusal(tmp_path), "clip.c3d", None, "POINT:USED", "holds no 3D points",
          "16 analog channels at 600 Hz and 2 force plates", "export the markers")


@pytest.mark.parametrize(("sidecar", "file", "line", "field", "phrases"), [
    ({"joint_map": BRICE_MAP, "frame_from": "row"}, "clip.dlc.csv", 2, "individuals",
     ["holds 2 individuals (leftHand, rightHand)", '"individual": "leftHand"']),
    ({"joint_map": BRICE_MAP, "individual": "lefthand", "frame_from": "row"},
     "clip.clip.json", None, "individual", ["'lefthand' is not in the individuals row"]),
    ({"joint_map": BRICE_MAP, "individual": "leftHand"}, "clip.dlc.csv", 5, "frame",
     ["is an image path", '"frame_from": "image_name"', '"frame_from": "row"']),
    ({"joint_map": BRICE_MAP, "individual": "leftHand", "frame_from": "image_name"},
     "clip.dlc.csv", 24, "frame", ["20 labelled images span 425 frames", '"frame_from": "row"']),
    ({"individual": "leftHand", "frame_from": "row"}, "clip.dlc.csv", 3, "bodyparts",
     ["unknown joint 'wristCenter'", "to null to ignore it"]),
    ({"individual": "leftHand", "frame_from": "row",
      "joint_map": BRICE_MAP | {"wristCentre": "wrist"}},
     "clip.clip.json", None, "joint_map", ["maps 'wristCentre', which clip.dlc.csv does not"]),
])
def test_dlc_labelled_data_refusals(real_tools, tmp_path, sidecar, file, line, field, phrases):
    put(real_tools, tmp_path, "dlc", SIDECAR_2D | sidecar)
    check(refusal(tmp_path), file, line, field, *phrases)


def test_mediapipe_two_hands_need_hand_index(real_tools, tmp_path):
    put(real_tools, tmp_path, "mediapipe", SIDECAR_2D | {"image": {"width": 1280,
                                                                   "height": 720}})
    check(refusal(tmp_path), "clip.mediapipe.csv", 23, "hand", "holds hands 0 and 1",
          '"hand_index": 0 (one of 0, 1)')


def test_mediapipe_normalised_needs_the_image_size(real_tools, tmp_path):
    put(real_tools, tmp_path, "mediapipe", SIDECAR_2D | {"hand_index": 0})
    check(refusal(tmp_path), "clip.clip.json", None, "image", '"image": {"width": W')


def test_openpose_without_tracking_has_no_person_id(real_tools, tmp_path):
    put(real_tools, tmp_path, "openpose", SIDECAR_2D | {"person": {"id": 1}})
    check(refusal(tmp_path), "clip.clip.json", None, "person", "no file of the folder holds",
          "its ids: -1", "select by index")


@pytest.mark.parametrize(("sidecar", "file", "field", "phrases"), [
    ({}, "clip.qtm.tsv", "MARKER_NAMES", ["unknown joint 'hand_top'"]),
    ({"fps": 30, "joint_map": GLOVE_TIPS | {"*": None}}, "clip.clip.json", "fps",
     ["records FREQUENCY 100 Hz", '"fps": 100']),
])
def test_qualisys_refusals(real_tools, tmp_path, sidecar, file, field, phrases):
    put(real_tools, tmp_path, "qtm", SIDECAR_3D | {"fps": 100} | sidecar)
    error = refusal(tmp_path)
    check(error, file, 10 if file.endswith(".tsv") else None, field, *phrases)


@pytest.mark.parametrize(("sidecar", "file", "field", "phrases"), [
    ({"frame_offset": "first"}, "clip.interhand.json", "capture",
     ["holds captures 2, 3, 4, 7", '"capture": "3"']),
    ({"capture": "3"}, "clip.interhand.json", "3.69148",
     ["frame ids start at 69148", '"frame_offset": "first"']),
    ({"capture": "4", "hand": "left", "frame_offset": "first"}, "clip.interhand.json",
     "4.joint_valid", ["capture 4 has no valid left-hand joint"]),
    ({"capture": "5", "frame_offset": "first"}, "clip.clip.json", "capture",
     ["'5', but clip.interhand.json holds captures 2, 3, 4, 7"]),
])
def test_interhand_refusals(real_tools, tmp_path, sidecar, file, field, phrases):
    put(real_tools, tmp_path, "interhand", SIDECAR_3D | sidecar)
    check(refusal(tmp_path), file, None, field, *phrases)
