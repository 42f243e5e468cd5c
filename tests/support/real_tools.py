"""The real tool files of ../shared/data/real-tools as inbox entries: their sidecars, the
joint maps their projects need, and the inbox a build of all of them reads (tests and
``benchmarks/real_captures.py``)."""

import json
import shutil
from pathlib import Path

SIDECAR_2D = {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
              "units": "mm", "camera": {"model": "orthographic"}}
SIDECAR_3D = {"skeleton": "mediapipe21", "hand": "right", "fps": 30, "subject": "s01",
              "units": "mm"}

#: The body parts of the DeepLabCut hands project, as canonical joints (REPORT.md §2.3).
BRICE_MAP = {"wristCenter": "wrist", "thumbStart": "thumb_mcp", "thumbCenter": "thumb_ip",
             "thumbEnd": "thumb_tip"} | {
    f"{finger}{part}": f"{finger}_{joint}" for finger in ("index", "middle", "ring", "little")
    for part, joint in (("Start", "mcp"), ("Center", "pip"), ("End", "tip"))}

GLOVE_MARKERS = ("hand_top", "hand_left", "hand_right", "thumb_tip", "thumb_middle",
                 "little_tip", "little_middle", "ring_tip", "ring_middle", "middle_middle",
                 "middle_tip", "index_tip", "index_middle", "right_elbow", "back_top",
                 "back_left", "back_right", "pillow_top", "pillow_left", "pillow_right",
                 "right_shoulder")
GLOVE_TIPS = {f"{f}_tip": f"{f}_tip" for f in ("thumb", "index", "middle", "ring", "little")}

SOURCES = {
    "openpose": ("openpose-hand", ".openpose"),
    "dlc": ("dlc-hands/CollectedData_Brice.csv", ".dlc.csv"),
    "mediapipe": ("mediapipe/hand_landmarks.csv", ".mediapipe.csv"),
    "optotrak": ("c3d/Optotrak.c3d", ".c3d"),
    "kistler": ("c3d/Kistler.c3d", ".c3d"),
    "qtm": ("qualisys-glove/recording.tsv", ".qtm.tsv"),
    "interhand": ("interhand/test_interhand2.6m_joint_3d.json", ".interhand.json"),
}


def put(real_tools: Path, inbox: Path, source: str, sidecar: dict,
        clip_id: str = "clip") -> Path:
    """Copy a real file into the inbox as ``<clip_id><suffix>`` beside its sidecar."""
    relative, suffix = SOURCES[source]
    inbox.mkdir(exist_ok=True)
    target = inbox / f"{clip_id}{suffix}"
    origin = real_tools / relative
    (shutil.copytree if origin.is_dir() else shutil.copy)(origin, target)
    (inbox / f"{clip_id}.clip.json").write_text(json.dumps(sidecar))
    return target


#: Two bone lengths a user of a 2D tool might know, mm.
KNOWN_BONES = {"bone_lengths": {"index_pip": 40.0, "thumb_cmc": 34.0}}


def tool_inbox(real_tools: Path, dhg_sample: Path, inbox: Path) -> Path:
    """Put every real tool file, and the DHG capture, into ``inbox`` as a user would.

    Stored as clips: the DHG capture, an InterHand frame, and the 2D tools' hands (OpenPose,
    DeepLabCut, MediaPipe) with :data:`KNOWN_BONES`; refused with a reason: the Qualisys
    glove (ten joints marked), two C3D files (no markers exported; truncated).
    """
    inbox.mkdir(parents=True, exist_ok=True)
    shutil.copy(dhg_sample, inbox / "dhg.dhg.txt")
    (inbox / "dhg.clip.json").write_text(json.dumps(SIDECAR_3D | {"skeleton": "dhg22"}))
    put(real_tools, inbox, "qtm", SIDECAR_3D | {"fps": 100, "joint_map": {
        "*": None, **GLOVE_TIPS, **{f"{f}_middle": f"{f}_pip" for f in (
            "index", "middle", "ring", "little")}, "thumb_middle": "thumb_ip"}},
        clip_id="glove")
    put(real_tools, inbox, "openpose", SIDECAR_2D | KNOWN_BONES | {"person": 0, "fps": 25},
        clip_id="signer")
    put(real_tools, inbox, "dlc", SIDECAR_2D | KNOWN_BONES | {
        "individual": "rightHand", "frame_from": "row", "joint_map": BRICE_MAP,
        "image": {"width": 852, "height": 480}}, clip_id="brice-right")
    put(real_tools, inbox, "mediapipe", SIDECAR_2D | KNOWN_BONES | {
        "hand_index": 0, "image": {"width": 1280, "height": 720}}, clip_id="mp-hand0")
    put(real_tools, inbox, "interhand", SIDECAR_3D | {"capture": "3", "frame_offset": "first"},
        clip_id="ih-cap3")
    put(real_tools, inbox, "kistler", SIDECAR_3D | {"fps": 60}, clip_id="kistler")
    put(real_tools, inbox, "optotrak", SIDECAR_3D | {"joint_map": {"*": None,
                                                                  "Marker_1": "wrist"}},
        clip_id="opto")
    return inbox
