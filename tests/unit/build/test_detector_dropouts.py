"""What real detectors drop is built, not refused: a joint never found, empty frames.

Small generated OpenPose and DeepLabCut files go through the build (library and CLI): the
clip is stored, the never-found joint placed by the hand model and marked filled, frames
at the ends left without positions, and the clip flagged saying both. Only a clip that
never shows enough of the palm to place a hand is refused. The real OpenPose sample, its
little fingertip never above 0.5 and two frames emptied, is built the same way.
"""

import json
import shutil

import numpy as np
from typer.testing import CliRunner

from handdb.build import BuildOptions, build_in_process
from handdb.cli import EXIT_QUARANTINED, app
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import dlc, openpose
from handdb.store import query
from handdb.synthetic import synthesize_clip

N_FRAMES = 30
#: The empty frames of the generated clips: two leading (kept unfilled), two interior
#: (bridged).
LEADING, INTERIOR = slice(0, 2), slice(12, 14)
NEVER_FOUND = "little_tip"


def _dropouts(clip):
    """The clip's points with the leading and interior frames emptied, ``(T, J, 2)``."""
    uv = clip.uv.copy()
    uv[LEADING] = np.nan
    uv[INTERIOR] = np.nan
    return uv


def _openpose_inbox(root, *, sidecar_extra=None):
    """An OpenPose folder whose little fingertip is never above its confidence threshold."""
    clip = synthesize_clip("wave", N_FRAMES, seed=4)
    skeleton = load_skeleton(clip.skeleton)
    confidence = np.full(clip.uv.shape[:2], 0.9)
    confidence[:, skeleton.index(NEVER_FOUND)] = 0.1
    root.mkdir()
    openpose.write(root / "signer.openpose", _dropouts(clip), confidence, skeleton,
                   hand=clip.hand)
    (root / "signer.clip.json").write_text(json.dumps(clip.sidecar() | (sidecar_extra or {})))
    return skeleton


def _rows(db, clip_id, where):
    return query(db, f"SELECT frame, joint, x, filled, fill_method, flagged FROM joints_3d "
                     f"WHERE clip_id = '{clip_id}' AND {where} ORDER BY frame").to_pylist()


def _check_stored(db, clip_id, reasons):
    assert any(f"{NEVER_FOUND} never detected: placed by the hand model" in r for r in reasons)
    assert any(f"2 of {N_FRAMES} frames (0-1) observe no point" in r for r in reasons)
    placed = _rows(db, clip_id, f"joint = '{NEVER_FOUND}' AND frame >= 2")
    assert len(placed) == N_FRAMES - 2
    assert all(r["filled"] and r["fill_method"] in ("chord", "rest-pose")
               and r["x"] is not None and r["flagged"] for r in placed)
    leading = _rows(db, clip_id, "frame < 2")
    assert leading and all(r["x"] is None and r["flagged"] and not r["filled"]
                           for r in leading)
    bridged = _rows(db, clip_id, f"frame >= {INTERIOR.start} AND frame < {INTERIOR.stop}")
    assert bridged and all(r["x"] is not None and r["filled"] for r in bridged)
    (clip,) = query(db, f"SELECT flagged, flag_reasons FROM clips WHERE clip_id = "
                        f"'{clip_id}'").to_pylist()
    assert clip["flagged"] and clip["flag_reasons"] == list(reasons)


def test_openpose_with_empty_frames_and_a_joint_never_found_is_stored_flagged(tmp_path):
    _openpose_inbox(tmp_path / "inbox")
    db = str(tmp_path / "db")
    summary = build_in_process(tmp_path / "inbox", db, BuildOptions(export_usd=False))
    assert list(summary.processed) == ["signer"] and not summary.refusals
    _check_stored(db, "signer", summary.flagged["signer"])


def test_dlc_with_a_body_part_all_nan_builds_through_the_cli(tmp_path):
    clip = synthesize_clip("wave", N_FRAMES, seed=5)
    skeleton = load_skeleton(clip.skeleton)
    uv = _dropouts(clip)
    uv[:, skeleton.index(NEVER_FOUND)] = np.nan
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    dlc.write(inbox / "hands.dlc.csv", uv, None, skeleton)
    (inbox / "hands.clip.json").write_text(json.dumps(clip.sidecar()))
    db = str(tmp_path / "db")
    result = CliRunner().invoke(app, ["build", "--inbox", str(inbox), "--db", db,
                                      "--runner", "local", "--no-usd"])
    assert result.exit_code == 0, result.output
    (row,) = query(db, "SELECT flag_reasons FROM clips").to_pylist()
    _check_stored(db, "hands", row["flag_reasons"])


def test_a_clip_that_never_shows_the_palm_is_refused_saying_so(tmp_path):
    clip = synthesize_clip("wave", N_FRAMES, seed=6)
    skeleton = load_skeleton(clip.skeleton)
    index_finger = [skeleton.index(j) for j in ("wrist", "index_mcp", "index_pip",
                                                 "index_dip", "index_tip")]
    uv = np.full_like(clip.uv, np.nan)
    uv[:, index_finger] = clip.uv[:, index_finger]
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    dlc.write(inbox / "finger.dlc.csv", uv, None, skeleton)
    (inbox / "finger.clip.json").write_text(json.dumps(clip.sidecar()))
    db = str(tmp_path / "db")
    result = CliRunner().invoke(app, ["build", "--inbox", str(inbox), "--db", db,
                                      "--runner", "local", "--no-usd"])
    assert result.exit_code == EXIT_QUARANTINED, result.output
    (row,) = query(db, "SELECT stage, reason FROM quarantine").to_pylist()
    assert row["stage"] == "gap_fill"
    assert "no frame observes 3 of those (the clip observes wrist, index_mcp)" in row["reason"]


def test_openpose_hand_points_count_from_openposes_own_threshold(tmp_path):
    """OpenPose's 0.2, not 0.5: a point at 0.3 is observed unless the sidecar says 0.5."""
    from handdb.ingest import discover, load_clip

    skeleton = _openpose_inbox(tmp_path / "inbox")
    folder = tmp_path / "inbox" / "signer.openpose"
    for path in folder.iterdir():
        doc = json.loads(path.read_text())
        for person in doc["people"]:
            points = person["hand_right_keypoints_2d"]
            points[3 * skeleton.index(NEVER_FOUND) + 2] = 0.3
        path.write_text(json.dumps(doc))
    (entry,) = discover(tmp_path / "inbox").clips
    clip = load_clip(entry)
    assert clip.min_confidence == 0.2
    detected = clip.observed.any(axis=1)
    assert detected.sum() == N_FRAMES - 4
    assert clip.observed[detected, skeleton.index(NEVER_FOUND)].all()
    strict = tmp_path / "strict"
    shutil.copytree(tmp_path / "inbox", strict)
    sidecar = strict / "signer.clip.json"
    sidecar.write_text(json.dumps(json.loads(sidecar.read_text()) | {"min_confidence": 0.5}))
    (entry,) = discover(strict).clips
    assert not load_clip(entry).observed[:, skeleton.index(NEVER_FOUND)].any()


def test_the_real_openpose_sample_with_empty_frames_is_stored_flagged(real_tools, tmp_path):
    """The left hand of the real sample, frames 2-3 emptied: its little fingertip is never
    above 0.5 (the threshold asked for here) in the frames left."""
    inbox = tmp_path / "inbox"
    inbox.mkdir()
    folder = inbox / "signer.openpose"
    shutil.copytree(real_tools / "openpose-hand", folder)
    for frame in (2, 3):
        path = folder / f"video_0000000000{frame:02d}_keypoints.json"
        path.write_text(json.dumps(json.loads(path.read_text()) | {"people": []}))
    (inbox / "signer.clip.json").write_text(json.dumps({
        "skeleton": "mediapipe21", "hand": "left", "fps": 25, "subject": "signer01",
        "units": "mm", "camera": {"model": "orthographic"}, "person": 0,
        "min_confidence": 0.5}))
    db = str(tmp_path / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert list(summary.processed) == ["signer"] and not summary.refusals
    assert any(f"{NEVER_FOUND} never detected: placed by the hand model" in r
               for r in summary.flagged["signer"])
    rows = _rows(db, "signer", "frame IN (2, 3)")
    assert len(rows) == 42 and all(r["x"] is not None and r["filled"] for r in rows)
