"""A corpus of broken and hostile inputs (REPORT §8 of issue 15), generated here: each is
refused with its file, line and field, before anything large is allocated or anything
outside the inbox is read, and the other clip of the inbox still loads."""

import io
import json
import os
import re
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

import c3d
import numpy as np
import pytest

from handdb.errors import InputError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import clip_content_hash, discover, load_clip, tracks_csv
from handdb.ingest.limits import MAX_FILE_BYTES, MAX_SIDECAR_BYTES
from tests.unit.ingest.conftest import SIDECAR, hand_track

SIDECAR_3D = {k: v for k, v in SIDECAR.items() if k != "camera"}
MEDIAPIPE21 = load_skeleton("mediapipe21")
HEADER = "frame,joint,u,v,confidence\n"
ROWS = "0,wrist,320.5,401.2,0.98\n0,index_tip,301.0,255.7,0.91\n1,wrist,321.0,400.8,0.97\n"
#: A line no refusal may quote: it sits in a file outside the inbox.
SECRET = "frame,joint,u,v,SECRET-1234"


def sidecar(inbox, clip_id="c1", text=None, **overrides):
    path = inbox / f"{clip_id}.clip.json"
    path.write_text(text if text is not None else json.dumps(SIDECAR | overrides))


def tracks(inbox, body, clip_id="c1", header=HEADER, **overrides):
    sidecar(inbox, clip_id, **overrides)
    (inbox / f"{clip_id}.tracks.csv").write_text(header + body)


def raw(inbox, name, data, **overrides):
    sidecar(inbox, name.split(".")[0], **overrides)
    (inbox / name).write_bytes(data)


def keypoints(points, people=1):
    hand = {"person_id": [-1], "hand_right_keypoints_2d": points,
            "hand_left_keypoints_2d": []}
    return json.dumps({"version": 1.3, "people": [hand] * people})


def openpose_folder(inbox, frames=3, people=(1, 1, 1), scale=1.0, **overrides):
    folder = inbox / "c1.openpose"
    folder.mkdir(parents=True)
    points = (np.c_[hand_track(MEDIAPIPE21)[0], np.full(21, 0.9)] * [scale, scale, 1.0])
    for frame in range(frames):
        (folder / f"v_{frame:012d}_keypoints.json").write_text(
            keypoints(points.ravel().tolist(), people[frame]))
    sidecar(inbox, **overrides)
    return folder


def mediapipe(inbox, doc, **overrides):
    sidecar(inbox, **({"image": {"width": 640, "height": 480}} | overrides))
    text = doc if isinstance(doc, str) else json.dumps(doc)
    (inbox / "c1.mediapipe.json").write_text(text)


LANDMARKS = [[0.5, 0.4, 0.0]] * 21


def c3d_bytes(labels=("wrist", "index_tip"), n_frames=3, rate=30.0):
    writer = c3d.Writer(point_rate=rate, point_units="mm")
    writer.set_point_labels(list(labels))
    frames = np.zeros((n_frames, len(labels), 5), dtype=np.float32)
    frames[..., :3] = 10.0
    writer.add_frames([(frame, np.zeros((0, 0), dtype=np.float32)) for frame in frames])
    buffer = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        writer.write(buffer)
    return buffer.getvalue()


def c3d_file(inbox, data, **overrides):
    sidecar(inbox, text=json.dumps(SIDECAR_3D | overrides))
    (inbox / "c1.c3d").write_bytes(data)


def patched(data, offset, value, fmt="<H"):
    data = bytearray(data)
    data[offset:offset + struct.calcsize(fmt)] = struct.pack(fmt, value)
    return bytes(data)


def dlc(inbox, text, **overrides):
    sidecar(inbox, **({"joint_map": {"Wrist": "wrist"}} | overrides))
    (inbox / "c1.dlc.csv").write_text(text)


DLC_HEADER = "scorer,S,S\nbodyparts,Wrist,Wrist\ncoords,x,y\n"
DLC_LABELLED = ("scorer,S,S\nbodyparts,Wrist,Wrist\ncoords,x,y\n"
                "labeled-data/v1/img001.png,1,2\nlabeled-data/v1/img002.png,1,2\n")


@dataclass(frozen=True)
class Case:
    """A broken input: how to write it, and the refusal expected (file name, line, field)."""

    write: object
    file: str
    line: int | None
    field: str | None
    message: str


CASES = {
    # frame numbers: bounded before any array is made of them
    "csv_frame_beyond_int64": Case(lambda d: tracks(d, "9223372036854775808,wrist,1,2,0.9\n"),
                                   "c1.tracks.csv", 2, "frame", "beyond handdb's limit"),
    "csv_frame_1e7": Case(lambda d: tracks(d, "10000000,wrist,1,2,0.9\n"), "c1.tracks.csv", 2,
                          "frame", "frame 10000000 is beyond handdb's limit of 1,000,000"),
    "csv_frame_2e9": Case(lambda d: tracks(d, "0,wrist,1,2,0.9\n2000000000,wrist,1,2,0.9\n"),
                          "c1.tracks.csv", 3, "frame", "beyond handdb's limit"),
    "csv_stray_frame": Case(
        lambda d: tracks(d, "".join(f"{t},wrist,1,2,0.9\n" for t in range(100))
                         + "100000,wrist,1,2,0.9\n"),
        "c1.tracks.csv", 102, "frame", "frame 100000 makes a clip of 100,001 frames of which "
        "only 101 carry a point"),
    "csv_stray_frame_within_the_sparse_limit": Case(
        lambda d: tracks(d, "".join(f"{t},wrist,1,2,0.9\n" for t in range(64))
                         + "5000,wrist,1,2,0.9\n"),
        "c1.tracks.csv", 66, "frame", "frame 5000 comes after 4,936 frames without a point "
        "\\(from frame 64\\), more than the 65 frames"),
    "csv_frame_float": Case(lambda d: tracks(d, "3.0,wrist,1,2,0.9\n"), "c1.tracks.csv", 2,
                            "frame", "'3.0' is not a whole frame number"),
    # numbers and text
    "csv_u_1e30": Case(lambda d: tracks(d, "0,wrist,1e30,2,0.9\n"), "c1.tracks.csv", 2, "u",
                       "1e\\+30 px is not a plausible coordinate"),
    "csv_u_nan": Case(lambda d: tracks(d, "0,wrist,nan,2,0.9\n"), "c1.tracks.csv", 2, "u",
                      "'nan' is not a finite number"),
    "csv_decimal_comma": Case(lambda d: tracks(d, '0,wrist,"320,5",401.2,0.98\n'),
                              "c1.tracks.csv", 2, None, "a decimal comma"),
    "csv_utf16": Case(lambda d: raw(d, "c1.tracks.csv", (HEADER + ROWS).encode("utf-16")),
                      "c1.tracks.csv", None, None, "is UTF-16 text; save it as UTF-8"),
    "csv_cr_only": Case(lambda d: raw(d, "c1.tracks.csv", b"frame,joint,u,v\r0,wrist,1,2\r"),
                        "c1.tracks.csv", None, None, "carriage returns alone"),
    "csv_nul": Case(lambda d: raw(d, "c1.tracks.csv", b"frame,joint,u,v\n0,wri\0st,1,2\n"),
                    "c1.tracks.csv", 2, None, "holds a NUL byte"),
    "csv_empty": Case(lambda d: tracks(d, "", header=""), "c1.tracks.csv", None, None,
                      "is empty"),
    "csv_header_only": Case(lambda d: tracks(d, ""), "c1.tracks.csv", 1, None,
                            "has a header but no data rows"),
    "csv_cut_row": Case(lambda d: tracks(d, ROWS + "2,wrist,32"), "c1.tracks.csv", 5, None,
                        "the file looks truncated"),
    "csv_long_cell_quoted_short": Case(
        lambda d: tracks(d, ROWS, header="x" * 500 + "\n"), "c1.tracks.csv", 1, "x" * 500,
        "unknown column 'x{37}\\.\\.\\.'; the header must be"),
    # the sidecar
    "side_duplicate_key": Case(lambda d: tracks(d, ROWS) or sidecar(
        d, text=json.dumps(SIDECAR)[:-1] + ', "fps": 3000}'), "c1.clip.json", None, "fps",
        "is given twice in one object"),
    "side_deep_nesting": Case(lambda d: tracks(d, ROWS) or sidecar(
        d, text='{"gap_fill": ' + "[" * 100000 + "]" * 100000 + "}"), "c1.clip.json", 1, None,
        "nests JSON 100001 levels deep \\(limit 64\\)"),
    "side_5000_digits": Case(lambda d: tracks(d, ROWS) or sidecar(
        d, text=json.dumps(SIDECAR).replace('"fps": 30', '"fps": ' + "9" * 5000)),
        "c1.clip.json", 1, None, "holds an integer of 5000 digits"),
    "side_fps_1e300": Case(lambda d: tracks(d, ROWS, fps=1e300), "c1.clip.json", None, "fps",
                           "not a plausible frame rate"),
    "side_fps_1e-300": Case(lambda d: tracks(d, ROWS, fps=1e-300), "c1.clip.json", None,
                            "fps", "not a plausible frame rate \\(1 to"),
    "side_bone_1e300": Case(lambda d: tracks(d, ROWS, bone_lengths={"index_pip": 1e300}),
                            "c1.clip.json", None, "bone_lengths.index_pip",
                            "1e\\+300 mm is not a plausible length here \\(from 1 to 500 mm\\)"),
    "side_bone_1e-300": Case(lambda d: tracks(d, ROWS, bone_lengths={"index_pip": 1e-300}),
                             "c1.clip.json", None, "bone_lengths.index_pip",
                             "not a plausible length here"),
    "side_hand_length_in_metres_as_mm": Case(lambda d: tracks(d, ROWS, hand_length=0.19),
                                             "c1.clip.json", None, "hand_length",
                                             "check the value and the sidecar's 'units'"),
    "side_fps_nan": Case(lambda d: tracks(d, ROWS) or sidecar(
        d, text=json.dumps(SIDECAR).replace('"fps": 30', '"fps": NaN')), "c1.clip.json", None,
        "fps", "must be a finite number, got NaN"),
    "side_image_huge": Case(lambda d: tracks(d, ROWS, image={"width": 200000, "height": 480}),
                            "c1.clip.json", None, "image.width", "not a plausible image side"),
    "side_key_of_another_format": Case(lambda d: tracks(d, ROWS, person=0), "c1.clip.json",
                                       None, "person", "only .openpose files read it"),
    "side_person_id_untracked": Case(lambda d: openpose_folder(d, person={"id": -1}),
                                     "c1.clip.json", None, "person.id", "without --tracking"),
    "side_hand_index_and_handedness": Case(
        lambda d: mediapipe(d, {"frames": []}, hand_index=0, handedness="Left"),
        "c1.clip.json", None, "handedness", "not both"),
    "side_too_large": Case(lambda d: tracks(d, ROWS) or sidecar(
        d, text=json.dumps(SIDECAR) + " " * MAX_SIDECAR_BYTES), "c1.clip.json", None, None,
        "handdb reads such files up to 1,048,576 bytes"),
    "side_joint_map_key_unused": Case(lambda d: tracks(d, ROWS, joint_map={"Wrist": None}),
                                      "c1.clip.json", None, "joint_map",
                                      "maps 'Wrist', which c1.tracks.csv does not name"),
    # OpenPose
    "op_frame_digits": Case(lambda d: (openpose_folder(d) / "v_99999999999999999999_keypoints"
                                       ".json").write_text(keypoints([])),
                            "v_99999999999999999999_keypoints.json", None, "frame",
                            "frame 99999999999999999999 is beyond"),
    "op_null_person": Case(lambda d: (openpose_folder(d) / "v_000000000001_keypoints.json")
                           .write_text('{"people": [null]}'), "v_000000000001_keypoints.json",
                           None, "people[0]", "must be an object, got null"),
    "op_two_people": Case(lambda d: openpose_folder(d, people=(1, 2, 1)),
                          "v_000000000001_keypoints.json", None, "people",
                          'holds 2 people; say which one with "person"'),
    "op_people_vary": Case(lambda d: openpose_folder(d, people=(2, 2, 1), person=1),
                           "v_000000000002_keypoints.json", None, "people",
                           "1 person here but 2 in v_000000000000_keypoints.json"),
    "op_normalised": Case(lambda d: openpose_folder(d, scale=1 / 1000),
                          "v_000000000000_keypoints.json", None,
                          "people[0].hand_right_keypoints_2d[little_tip].x",
                          'normalised to the image.*--keypoint_scale 3 or 4.*'
                          '"coordinates": "normalized"'),
    "op_normalised_without_image": Case(
        lambda d: openpose_folder(d, scale=1 / 1000, coordinates="normalized"),
        "c1.clip.json", None, "image", "needs the image size"),
    "op_deep_nesting": Case(lambda d: (openpose_folder(d) / "v_000000000001_keypoints.json")
                            .write_text('{"people": ' + "[" * 50000 + "]" * 50000 + "}"),
                            "v_000000000001_keypoints.json", 1, None, "nests JSON"),
    # MediaPipe
    "mp_frame_2e9": Case(lambda d: mediapipe(d, {"frames": [
        {"frame": 0, "landmarks": LANDMARKS}, {"frame": 2000000000, "landmarks": LANDMARKS}]}),
        "c1.mediapipe.json", None, "frames[1].frame", "frame 2000000000 is beyond"),
    "mp_frame_31_digits": Case(lambda d: mediapipe(
        d, '{"frames": [{"frame": 1' + "0" * 30 + ', "landmarks": null}]}'),
        "c1.mediapipe.json", 1, None, "holds an integer of 31 digits"),
    "mp_visibility_logit": Case(lambda d: mediapipe(d, {"frames": [
        {"frame": 0, "landmarks": [p + [3.2] for p in LANDMARKS]}]}), "c1.mediapipe.json",
        None, "frames[0].landmarks", "visibility 3.2 is not in \\[0, 1\\] \\(a logit\\?\\)"),
    "mp_pixels_as_normalised": Case(lambda d: mediapipe(d, {"frames": [
        {"frame": 0, "landmarks": [[300.0, 200.0, 0.0]] * 21}]}), "c1.mediapipe.json", None,
        "frames[0].landmarks[0]", 'landmark 0 at x=300.*"coordinates": "pixels"'),
    "mp_hands_without_frames": Case(lambda d: mediapipe(d, [[{"x": 0.1, "y": 0.2}] * 21]),
                                    "c1.mediapipe.json", None, "frames",
                                    "list of hands without frame numbers"),
    # C3D, pre-checked before the c3d package reads it
    "c3d_empty": Case(lambda d: c3d_file(d, b""), "c1.c3d", None, None,
                      "is not a C3D file \\(it is 0 bytes"),
    "c3d_text": Case(lambda d: c3d_file(d, b"frame,joint,x,y,z\n" * 40), "c1.c3d", None, None,
                     "its second byte is not the C3D mark"),
    "c3d_header_only": Case(lambda d: c3d_file(d, c3d_bytes()[:512]), "c1.c3d", None, None,
                            "ends before its parameter section"),
    "c3d_cut_parameters": Case(lambda d: c3d_file(d, c3d_bytes()[:1000]), "c1.c3d", None, None,
                               "ends inside its parameter section \\(1000 of at least"),
    "c3d_cut_data": Case(lambda d: c3d_file(d, c3d_bytes(n_frames=40)[:2100]), "c1.c3d", None,
                         "POINT:FRAMES", "holds 1 frames of POINT data, but its header says "
                         "40.*truncated"),
    "c3d_point_count_lies": Case(lambda d: c3d_file(d, patched(c3d_bytes(), 2, 60000)),
                                 "c1.c3d", None, None, "is not a readable C3D file"),
    "c3d_rate": Case(lambda d: c3d_file(d, c3d_bytes(rate=100.0)), "c1.clip.json", None,
                     "fps", 'records POINT:RATE 100 Hz; set "fps": 100'),
    "c3d_extra_label": Case(lambda d: c3d_file(d, c3d_bytes(labels=("wrist", "LASI"))),
                            "c1.c3d", None, "POINT:LABELS", "unknown joint 'LASI'"),
    # DeepLabCut
    "dlc_header_only": Case(lambda d: dlc(d, DLC_HEADER), "c1.dlc.csv", 3, None,
                            "has header rows but no data rows"),
    "dlc_image_path": Case(lambda d: dlc(d, DLC_LABELLED), "c1.dlc.csv", 4, "frame",
                           'is an image path.*"frame_from": "image_name"'),
    "dlc_image_twice": Case(lambda d: dlc(d, DLC_LABELLED.replace("img002", "img1"),
                                          frame_from="image_name"), "c1.dlc.csv", 5, "frame",
                            "image number 1 is also on line 4"),
    "dlc_two_videos": Case(lambda d: dlc(d, DLC_LABELLED.replace("v1/img002", "v2/img002"),
                                         frame_from="image_name"), "c1.dlc.csv", 5, "frame",
                           "more than one video folder"),
    "dlc_individual_absent": Case(lambda d: dlc(d, DLC_HEADER + "0,1,2\n", individual="hand1"),
                                  "c1.clip.json", None, "individual", "has no individuals row"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_broken_input_is_refused_and_the_rest_loads(tmp_path, name, write_sidecar,
                                                    mediapipe21, noisy_track):
    case = CASES[name]
    uv, confidence = noisy_track
    write_sidecar(tmp_path, "good")
    tracks_csv.write(tmp_path / "good.tracks.csv", uv, confidence, mediapipe21)
    case.write(tmp_path)
    scan = discover(tmp_path)
    assert scan.refused == ()
    entries = {entry.clip_id: entry for entry in scan.clips}
    with pytest.raises(InputError) as info:
        load_clip(entries["c1"])
    error = info.value
    assert (Path(error.file).name, error.line, error.field) == (case.file, case.line,
                                                                case.field), str(error)
    assert error.clip_id == "c1"
    assert "None" not in error.reason
    assert re.search(case.message, error.reason), error.reason
    assert load_clip(entries["good"]).n_frames == uv.shape[0]


def outside_file(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.tracks.csv").write_text(SECRET + "\n0,wrist,1,2,3\n")
    return outside / "secret.tracks.csv"


def link_track(inbox, tmp_path):
    sidecar(inbox)
    os.symlink(outside_file(tmp_path), inbox / "c1.tracks.csv")


def link_sidecar(inbox, tmp_path):
    (inbox / "c1.tracks.csv").write_text(HEADER + ROWS)
    side = tmp_path / "outside-side.json"
    side.write_text(json.dumps(SIDECAR))
    os.symlink(side, inbox / "c1.clip.json")


def link_inside_openpose(inbox, tmp_path):
    folder = openpose_folder(inbox)
    os.symlink(outside_file(tmp_path), folder / "x_000000000007_keypoints.json")


def link_openpose_folder(inbox, tmp_path):
    outside = tmp_path / "outside-op"
    openpose_folder(outside.parent / "staging")
    (outside.parent / "staging" / "c1.openpose").rename(outside)
    sidecar(inbox)
    os.symlink(outside, inbox / "c1.openpose")


SCAN_CASES = {
    "id_trailing_newline": (lambda d, t: tracks(d, ROWS, clip_id="abc\n"), "abc\n.clip.json",
                            "clip_id", "clip id 'abc\\\\n' is not allowed"),
    "id_case_twins": (lambda d, t: tracks(d, ROWS, clip_id="Clip")
                      or tracks(d, ROWS, clip_id="clip"), "clip.tracks.csv", "clip_id",
                      "clip ids 'Clip' and 'clip' differ only in case"),
    "link_track_outside": (link_track, "c1.tracks.csv", None,
                           "is a symbolic link to .*secret.tracks.csv, outside the inbox"),
    "link_sidecar_outside": (link_sidecar, "c1.clip.json", None, "outside the inbox"),
    "link_inside_openpose": (link_inside_openpose, "x_000000000007_keypoints.json", None,
                             "outside the inbox"),
    "link_openpose_folder": (link_openpose_folder, "c1.openpose", None, "outside the inbox"),
    "link_dev_zero": (lambda d, t: sidecar(d) or os.symlink("/dev/zero", d / "c1.tracks.csv"),
                      "c1.tracks.csv", None, "symbolic link to /dev/zero, outside the inbox"),
    "link_dangling": (lambda d, t: sidecar(d) or os.symlink(d / "nowhere", d / "c1.tracks.csv"),
                      "c1.tracks.csv", None, "which does not exist"),
    "link_loop": (lambda d, t: sidecar(d) or os.symlink(d / "c1.tracks.csv",
                                                        d / "c1.tracks.csv"),
                  "c1.tracks.csv", None, "leads back to itself"),
    "sidecar_folder": (lambda d, t: (d / "c1.clip.json").mkdir() or
                       (d / "c1.tracks.csv").write_text(HEADER + ROWS), "c1.clip.json", None,
                       "is a folder; an inbox input must be a file"),
}


@pytest.mark.parametrize("name", list(SCAN_CASES))
def test_unsafe_entries_are_refused_by_the_scan_without_being_read(tmp_path, name,
                                                                   write_sidecar, mediapipe21,
                                                                   noisy_track):
    write, file, field, message = SCAN_CASES[name]
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    uv, confidence = noisy_track
    write_sidecar(inbox, "good")
    tracks_csv.write(inbox / "good.tracks.csv", uv, confidence, mediapipe21)
    write(inbox, tmp_path)
    scan = discover(inbox)
    assert [entry.clip_id for entry in scan.clips] == ["good"]
    refused = {Path(error.file).name: error for error in scan.refused}
    assert file in refused, sorted(refused)
    assert refused[file].field == field and re.search(message, refused[file].reason)
    assert not any("SECRET" in error.reason for error in scan.refused)
    assert load_clip(scan.clips[0]).n_frames == uv.shape[0]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_named_pipe_is_refused_without_opening_it(tmp_path):
    sidecar(tmp_path)
    os.mkfifo(tmp_path / "c1.tracks.csv")
    (error,) = discover(tmp_path).refused
    assert "is a named pipe; an inbox input must be a regular file" in error.reason


def test_readers_refuse_devices_and_oversized_files_before_reading(tmp_path, spec_for,
                                                                   mediapipe21):
    spec = spec_for(tmp_path)
    with pytest.raises(InputError, match="is not a regular file \\(a character device\\)"):
        tracks_csv.read(Path("/dev/zero"), spec, mediapipe21)
    huge = tmp_path / "huge.tracks.csv"
    with huge.open("wb") as handle:
        handle.truncate(MAX_FILE_BYTES + 1)
    with pytest.raises(InputError, match="handdb reads such files up to 2,147,483,648 bytes"):
        tracks_csv.read(huge, spec, mediapipe21)


def test_hidden_files_in_an_openpose_folder_are_neither_read_nor_hashed(tmp_path):
    folder = openpose_folder(tmp_path)
    entry = discover(tmp_path).clips[0]
    first, clip = clip_content_hash(entry), load_clip(entry)
    (folder / "._v_000000000000_keypoints.json").write_bytes(b"\0\5\26\7Mac OS X")
    (folder / "sub").mkdir()
    (folder / "sub" / "v_000000000009_keypoints.json").write_text(keypoints([]))
    assert clip_content_hash(entry) == first
    np.testing.assert_array_equal(load_clip(entry).uv, clip.uv)
    (folder / "v_000000000001_keypoints.json").write_text(keypoints([]))
    assert clip_content_hash(entry) != first


@pytest.mark.parametrize(("coordinates", "scale", "offset"), [("normalized", 1.0, 0.0),
                                                               ("normalized_signed", 0.5, 0.5)])
def test_openpose_normalised_coordinates_with_the_image_size(tmp_path, coordinates, scale,
                                                             offset):
    openpose_folder(tmp_path, scale=1 / 1000, coordinates=coordinates,
                    image={"width": 1000, "height": 1000})
    clip = load_clip(discover(tmp_path).clips[0])
    wrist = hand_track(MEDIAPIPE21)[0, 0]
    np.testing.assert_allclose(clip.uv[0, 0], (wrist / 1000 * scale + offset) * 1000)


def test_all_zero_visibility_is_no_confidence(tmp_path):
    mediapipe(tmp_path, {"frames": [{"frame": 0, "landmarks": [p + [0.0] for p in LANDMARKS]}]})
    clip = load_clip(discover(tmp_path).clips[0])
    assert np.isnan(clip.confidence).all() and clip.observed.all()


def test_c3d_labels_padded_with_nuls_are_stripped(tmp_path):
    data = c3d_bytes(labels=("wrist", "index_tip"))
    c3d_file(tmp_path, data.replace(b"wrist    ", b"wrist\0\0  ", 1))
    clip = load_clip(discover(tmp_path).clips[0])
    assert np.isfinite(clip.markers[:, 0]).all()


def test_dlc_split_index_columns_never_count_empty_cells_as_individuals(tmp_path):
    text = ("scorer,,,S,S\nindividuals,,,hand1,hand1\nbodyparts,,,Wrist,Wrist\ncoords,,,x,y\n"
            "labeled-data,v1,img004.png,1,2\nlabeled-data,v1,img005.png,3,4\n")
    dlc(tmp_path, text, frame_from="image_name")
    clip = load_clip(discover(tmp_path).clips[0])
    assert clip.n_frames == 6
    np.testing.assert_array_equal(clip.uv[4:, 0], [[1, 2], [3, 4]])


def test_a_video_beside_openpose_keypoints_is_neither_read_nor_hashed(tmp_path):
    folder = openpose_folder(tmp_path)
    entry = discover(tmp_path).clips[0]
    first = clip_content_hash(entry)
    with (folder / "video.mp4").open("wb") as video:
        video.truncate(2 * MAX_FILE_BYTES)  # sparse: no disk, and never read
    assert clip_content_hash(entry) == first
    assert load_clip(entry).n_frames == 3


def test_an_oversized_track_file_is_refused_by_the_hash_before_it_is_read(tmp_path):
    tracks(tmp_path, ROWS)
    with (tmp_path / "c1.tracks.csv").open("r+b") as track:
        track.truncate(MAX_FILE_BYTES + 1)
    [entry] = discover(tmp_path).clips
    with pytest.raises(InputError, match="bytes; handdb reads such files up to") as info:
        clip_content_hash(entry)
    assert Path(info.value.file).name == "c1.tracks.csv"
