import json

import numpy as np
import pyarrow as pa
import pytest

from handdb.errors import InputError, RegistryError
from handdb.ingest import (
    InputFormat,
    clip_content_hash,
    discover,
    load_clip,
    maya,
    openpose,
    register_format,
    tracks_2d_table,
    tracks_csv,
    truth_3d_table,
    truth_csv,
)
from handdb.store.tables import schema


def read_test_xray(path):
    return path


@pytest.fixture
def inbox(tmp_path, write_sidecar, mediapipe21, noisy_track):
    """An inbox with two good clips, one with ground truth."""
    uv, confidence = noisy_track
    write_sidecar(tmp_path, "s01_grasp")
    tracks_csv.write(tmp_path / "s01_grasp.tracks.csv", uv, confidence, mediapipe21)
    truth = np.random.default_rng(5).normal(0.0, 40.0, uv.shape[:2] + (3,))
    truth_csv.write(tmp_path / "s01_grasp.truth.csv", truth, mediapipe21)
    write_sidecar(tmp_path, "s02_wave", hand="left")
    openpose.write(tmp_path / "s02_wave.openpose", uv, confidence, mediapipe21, hand="left")
    return tmp_path


def test_discover_groups_clip_files(inbox):
    (inbox / "README.txt").write_text("not an input")
    (inbox / ".hidden.tracks.csv").write_text("frame,joint,u,v\n")
    scan = discover(inbox)
    assert scan.refused == ()
    grasp, wave = scan.clips
    assert (grasp.clip_id, grasp.track_format, grasp.truth_format) == (
        "s01_grasp", "tracks_csv", "truth_csv")
    assert grasp.paths == (inbox / "s01_grasp.clip.json", inbox / "s01_grasp.tracks.csv",
                           inbox / "s01_grasp.truth.csv")
    assert (wave.clip_id, wave.track_format, wave.truth) == ("s02_wave", "openpose", None)


def test_discover_refuses_entries_that_do_not_make_a_clip(inbox, write_sidecar):
    (inbox / "orphan.dlc.csv").write_text("scorer\n")
    write_sidecar(inbox, "lonely")
    (inbox / "s01_grasp.mediapipe.json").write_text("{}")
    (inbox / "bad..id.tracks.csv").write_text("frame,joint,u,v\n")
    (inbox / "we$ird.clip.json").write_text("{}")
    scan = discover(inbox)
    assert [entry.clip_id for entry in scan.clips] == ["s02_wave"]
    refused = {e.file.rsplit("/", 1)[-1]: e.reason for e in scan.refused}
    assert set(refused) == {"orphan.dlc.csv", "lonely.clip.json", "s01_grasp.tracks.csv",
                            "bad..id.tracks.csv", "we$ird.clip.json"}
    assert "has no sidecar: add orphan.clip.json" in refused["orphan.dlc.csv"]
    assert "has no track file" in refused["lonely.clip.json"]
    assert "two track files" in refused["s01_grasp.tracks.csv"]
    assert "no '..'" in refused["bad..id.tracks.csv"]
    assert "not allowed" in refused["we$ird.clip.json"]


@pytest.mark.parametrize(("name", "hint"), [
    ("hand.h5", "DeepLabCut's HDF5 table; handdb reads the CSV DeepLabCut writes beside it "
                "with save_as_csv=True, renamed hand.dlc.csv"),
    ("hand.csv", "name a CSV by its layout, hand.tracks.csv"),
    ("hand.keypoints.json", "OpenPose's files go in a folder hand.openpose"),
])
def test_a_clip_whose_file_no_format_reads_is_told_what_to_rename(tmp_path, write_sidecar,
                                                                  name, hint):
    write_sidecar(tmp_path, "hand")
    (tmp_path / name).write_bytes(b"\x89HDF\r\n")
    write_sidecar(tmp_path, "hand.2")
    (tmp_path / "hand.2.tracks.csv").write_text("frame,joint,u,v\n0,wrist,1,2\n")
    scan = discover(tmp_path)
    assert [entry.clip_id for entry in scan.clips] == ["hand.2"]
    (error,) = scan.refused
    assert f"'{name}' is not read: " in error.reason and hint in error.reason
    assert "hand.2" not in error.reason


def test_maya_export_and_a_truth_file_are_two_truths(tmp_path, write_sidecar):
    write_sidecar(tmp_path, "m", skeleton="thesis21")
    (tmp_path / "m.maya.txt").write_text("j0 0 1 2 3\n")
    (tmp_path / "m.truth.csv").write_text("frame,joint,x,y,z\n")
    scan = discover(tmp_path)
    assert scan.clips == ()
    assert "two sources of ground truth" in scan.refused[0].reason


def test_other_readers_formats_are_handed_over(inbox):
    register_format(InputFormat(name="test_xray", suffix=".test_xray.csv", kind="xray",
                                read=read_test_xray))
    (inbox / "subject1.test_xray.csv").write_text("bone,length\n")
    scan = discover(inbox)
    assert scan.others == {"test_xray": (inbox / "subject1.test_xray.csv",)}
    assert len(scan.clips) == 2 and not scan.refused


def test_registering_a_clashing_suffix_is_refused():
    with pytest.raises(RegistryError, match="clashes"):
        register_format(InputFormat(name="other_csv", suffix=".tracks.csv", kind="tracks",
                                    read=print))


def test_discover_needs_a_folder(tmp_path):
    with pytest.raises(InputError, match="is not a folder"):
        discover(tmp_path / "nowhere")


def test_load_clip_assembles_dense_arrays_and_truth(inbox, noisy_track):
    uv, confidence = noisy_track
    grasp = load_clip(discover(inbox).clips[0])
    assert grasp.clip_id == "s01_grasp" and grasp.source_format == "tracks_csv"
    assert grasp.source_files == tuple(str(inbox / f"s01_grasp{s}") for s in
                                       (".clip.json", ".tracks.csv", ".truth.csv"))
    reported = np.isfinite(confidence)
    np.testing.assert_array_equal(grasp.uv, np.where(reported[..., None], uv, np.nan))
    np.testing.assert_array_equal(grasp.confidence, confidence)
    assert grasp.truth.shape == uv.shape[:2] + (3,) and np.isfinite(grasp.truth).all()


def test_tables_hold_the_rows_as_ingested(inbox, noisy_track):
    uv, confidence = noisy_track
    grasp, wave = (load_clip(entry) for entry in discover(inbox).clips)
    tracks = tracks_2d_table(grasp)
    assert tracks.schema.equals(schema("tracks_2d"))
    assert tracks.num_rows == uv.shape[0] * uv.shape[1]
    hidden = ~np.isfinite(uv).all(axis=-1)
    assert tracks.column("u").null_count == hidden.sum()
    assert tracks.column("confidence").null_count == 0
    low = pa.compute.less(tracks.column("confidence"), 0.5)
    assert pa.compute.sum(low).as_py() == (confidence < 0.5).sum(), "low confidence is kept"
    truth = truth_3d_table(grasp)
    assert truth.schema.equals(schema("truth_3d")) and truth.num_rows == tracks.num_rows
    assert truth_3d_table(wave) is None
    assert set(tracks_2d_table(wave).column("frame").to_pylist()) == set(range(12)) - {3}


def test_maya_clip_has_track_and_truth_from_one_file(tmp_path, write_sidecar, thesis21):
    xyz = np.random.default_rng(6).normal(size=(3, 21, 3))
    write_sidecar(tmp_path, "clench", skeleton="thesis21", units="cm")
    maya.write(tmp_path / "clench.maya.txt", xyz, thesis21)
    clip = load_clip(discover(tmp_path).clips[0])
    np.testing.assert_array_equal(clip.truth, xyz)
    np.testing.assert_array_equal(clip.uv, xyz[..., :2])
    assert clip.observed.all()


def test_content_hash_follows_bytes_and_names(inbox):
    entry = discover(inbox).clips[0]
    first = clip_content_hash(entry)
    assert clip_content_hash(discover(inbox).clips[0]) == first == load_clip(entry).content_hash
    sidecar = json.loads(entry.sidecar.read_text())
    entry.sidecar.write_text(json.dumps(sidecar | {"fps": 60}))
    assert clip_content_hash(entry) != first
    entry.sidecar.write_text(json.dumps(sidecar))
    assert clip_content_hash(entry) == first
    for path in entry.paths:
        path.rename(path.with_name(path.name.replace("s01_grasp", "s01_grip")))
    assert clip_content_hash(discover(inbox).clips[0]) != first


def test_openpose_hash_covers_every_frame_file(inbox):
    entry = discover(inbox).clips[1]
    first = clip_content_hash(entry)
    frame_file = sorted(entry.tracks.iterdir())[5]
    frame_file.write_text(frame_file.read_text().replace("1.3", "1.2", 1))
    assert clip_content_hash(entry) != first


@pytest.mark.parametrize(("sidecar", "field", "message"), [
    ({"fps": "30"}, "fps", "must be a finite number"),
    ({"skeleton": "mano16"}, "skeleton", "unknown skeleton 'mano16'"),
    ({"hand": "both"}, "hand", "must be one of left, right"),
    ({"units": "furlong"}, "units", "must be one of"),
    ({"camera": {"model": "pinhole", "fx": 500}}, "camera", "needs fy, cx, cy"),
    ({"min_confidence": 2}, "min_confidence", r"must lie in \[0, 1\]"),
    ({"joint_map": {"Wrist": "wristt"}}, "joint_map", "not a joint"),
])
def test_bad_sidecars_are_refused_by_load_clip(inbox, write_sidecar, sidecar, field, message):
    write_sidecar(inbox, "s01_grasp", **sidecar)
    with pytest.raises(InputError, match=message) as info:
        load_clip(discover(inbox).clips[0])
    error = info.value
    assert (error.file, error.field, error.clip_id) == (
        str(inbox / "s01_grasp.clip.json"), field, "s01_grasp")


def test_truncated_sidecar_and_bad_tracks_carry_the_clip_id(inbox):
    (inbox / "s01_grasp.clip.json").write_text('{"skeleton": "mediapipe21",\n "hand": ')
    with pytest.raises(InputError, match="not valid JSON") as info:
        load_clip(discover(inbox).clips[0])
    assert info.value.line == 2
    (inbox / "s02_wave.openpose" / "extra_000000000099_keypoints.json").write_text("{")
    with pytest.raises(InputError) as info:
        load_clip(discover(inbox).clips[1])
    assert info.value.clip_id == "s02_wave"


def test_a_track_file_without_any_point_is_refused(tmp_path, write_sidecar, mediapipe21):
    write_sidecar(tmp_path, "empty")
    openpose.write(tmp_path / "empty.openpose", np.full((3, 21, 2), np.nan), None, mediapipe21,
                   hand="right")
    with pytest.raises(InputError, match="holds no point of the hand"):
        load_clip(discover(tmp_path).clips[0])
