"""The acceptance test of issue 2: one clip in three formats ingests to the same points."""

import numpy as np
import pytest

from handdb.ingest import discover, dlc, load_clip, openpose, tracks_csv

TOOL_NAMES = {"wrist": "Wrist", "index_tip": "IndexFingerTip"}


@pytest.fixture
def three_format_inbox(tmp_path, write_sidecar, mediapipe21, noisy_track):
    uv, confidence = noisy_track
    tracks_csv.write(tmp_path / "as_csv.tracks.csv", uv, confidence, mediapipe21)
    openpose.write(tmp_path / "as_openpose.openpose", uv, confidence, mediapipe21, hand="right")
    dlc.write(tmp_path / "as_dlc.dlc.csv", uv, confidence, mediapipe21, bodyparts=TOOL_NAMES)
    write_sidecar(tmp_path, "as_csv")
    # OpenPose's own threshold is 0.2 (handdb.clip.FORMAT_MIN_CONFIDENCE): ask for the others'
    write_sidecar(tmp_path, "as_openpose", min_confidence=0.5)
    write_sidecar(tmp_path, "as_dlc", joint_map={v: k for k, v in TOOL_NAMES.items()})
    return tmp_path


def test_one_clip_in_three_formats_gives_the_same_observed_points(three_format_inbox,
                                                                  noisy_track):
    uv, confidence = noisy_track
    scan = discover(three_format_inbox)
    assert not scan.refused
    clips = {entry.track_format: load_clip(entry) for entry in scan.clips}
    assert sorted(clips) == ["dlc", "openpose", "tracks_csv"]
    expected = np.isfinite(uv).all(axis=-1) & (confidence >= 0.5)
    assert 0 < expected.sum() < expected.size
    for clip in clips.values():
        assert clip.uv.shape == uv.shape
        np.testing.assert_array_equal(clip.observed, expected)
        np.testing.assert_array_equal(clip.uv[clip.observed], uv[expected])


def test_low_confidence_threshold_comes_from_the_sidecar(three_format_inbox, write_sidecar,
                                                         noisy_track):
    uv, confidence = noisy_track
    write_sidecar(three_format_inbox, "as_openpose", min_confidence=0.1)
    entry = next(e for e in discover(three_format_inbox).clips if e.clip_id == "as_openpose")
    np.testing.assert_array_equal(load_clip(entry).observed, np.isfinite(uv).all(axis=-1))
