"""The plausibility gate: real and synthetic hands pass, what no hand could do is flagged."""

import json
import warnings

import numpy as np
import pytest

from handdb.hand.skeletons import frame_bone_lengths, load_skeleton
from handdb.synthetic import synthesize_clip
from handdb.validation.plausibility import (
    assess,
    check_joint_order,
    flexion_angles,
    persistent_frames,
)

MEDIAPIPE = load_skeleton("mediapipe21")

#: InterHand2.6M's 21 joints of one hand, in its order (tip to base per finger, wrist last).
INTERHAND_ORDER = (
    "thumb_tip", "thumb_ip", "thumb_mcp", "thumb_cmc", "index_tip", "index_dip", "index_pip",
    "index_mcp", "middle_tip", "middle_dip", "middle_pip", "middle_mcp", "ring_tip",
    "ring_dip", "ring_pip", "ring_mcp", "little_tip", "little_dip", "little_pip",
    "little_mcp", "wrist",
)


def lengths_of(clip):
    return np.array([clip.bone_lengths.get(j, np.nan) for j in MEDIAPIPE.joints])


@pytest.fixture(scope="module")
def clip():
    return synthesize_clip("random", 120, seed=2)


@pytest.mark.parametrize("seed", range(6))
def test_hands_of_the_population_pass(seed):
    clip = synthesize_clip("random", 200, seed=seed, hand="left" if seed % 2 else "right")
    verdict = assess(MEDIAPIPE, "mm", clip.hand, lengths_of(clip), clip.xyz)
    assert not verdict.flagged, verdict.reasons
    assert not verdict.rows.any()


def test_real_interhand_hands_pass(real_tools):
    doc = json.loads((real_tools / "interhand" / "test_interhand2.6m_joint_3d.json").read_text())
    checked = 0
    for frames in doc.values():
        for frame in frames.values():
            world = np.array(frame["world_coord"])
            valid = np.array(frame["joint_valid"]).ravel() > 0
            for hand, first in (("right", 0), ("left", 21)):
                if not valid[first:first + 21].all():
                    continue
                points = world[first:first + 21][[INTERHAND_ORDER.index(j)
                                                  for j in MEDIAPIPE.joints]]
                lengths = frame_bone_lengths(points[None], MEDIAPIPE)[0]
                verdict = assess(MEDIAPIPE, "mm", hand, lengths, points[None])
                assert not verdict.flagged, verdict.reasons
                checked += 1
    assert checked >= 4


def test_the_noisy_dhg_tracker_is_flagged_for_what_no_hand_does(dhg_mm):
    dhg = load_skeleton("dhg22")
    lengths = np.full(dhg.n_joints, np.nan)
    bones = dhg.bones[:, 1]
    lengths[bones] = np.nanmedian(frame_bone_lengths(dhg_mm, dhg)[:, bones], axis=0)
    verdict = assess(dhg, "mm", "right", lengths, dhg_mm)
    assert verdict.flagged
    assert any("range of motion" in reason for reason in verdict.reasons)
    angles = flexion_angles(dhg, dhg_mm, "right")
    assert np.nanmin(angles[("index", "dip", "flexion")]) < -60  # a DIP bent far backwards


def test_an_impossible_metacarpal_and_phalanges_are_flagged(clip):
    lengths = lengths_of(clip)
    lengths[MEDIAPIPE.index("index_mcp")] = 222.0
    lengths[MEDIAPIPE.index("index_pip")] = 142.0
    verdict = assess(MEDIAPIPE, "mm", "right", lengths, None, n_frames=clip.n_frames)
    text = " ".join(verdict.reasons)
    assert "index_mcp is 222 mm" in text and "index_pip is 142 mm" in text
    assert verdict.rows[:, MEDIAPIPE.index("index_mcp")].all()
    assert not verdict.rows[:, MEDIAPIPE.index("ring_pip")].any()


def test_a_middle_phalanx_longer_than_the_proximal_is_flagged(clip):
    lengths = lengths_of(clip)
    pip, dip = MEDIAPIPE.index("ring_pip"), MEDIAPIPE.index("ring_dip")
    lengths[pip], lengths[dip] = lengths[dip], lengths[pip]
    verdict = assess(MEDIAPIPE, "mm", "right", lengths, None, n_frames=clip.n_frames)
    assert any("ring finger's phalanges are out of proportion" in r for r in verdict.reasons)


def bent_backwards(xyz, frames):
    """``xyz`` with the middle finger's PIP bent 100 degrees backwards in ``frames``."""
    xyz = xyz.copy()
    pip, dip, tip = MEDIAPIPE.indices(["middle_pip", "middle_dip", "middle_tip"])
    mcp = MEDIAPIPE.index("middle_mcp")
    wrist, index, little = MEDIAPIPE.indices(["wrist", "index_mcp", "little_mcp"])
    part = xyz[frames]
    normal = np.cross(part[:, index] - part[:, wrist], part[:, little] - part[:, wrist])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    along = (part[:, pip] - part[:, mcp]) / np.linalg.norm(part[:, pip] - part[:, mcp],
                                                             axis=-1, keepdims=True)
    backwards = np.cos(np.radians(100)) * along - np.sin(np.radians(100)) * normal
    part[:, dip] = part[:, pip] + 25.0 * backwards
    part[:, tip] = part[:, dip] + 20.0 * backwards
    xyz[frames] = part
    return xyz


def test_fingers_bent_backwards_are_flagged(clip):
    xyz = bent_backwards(clip.xyz, slice(None))
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(clip), xyz)
    assert any("middle PIP" in reason for reason in verdict.reasons)
    assert verdict.rows[:, 0].all()


@pytest.mark.parametrize("start", [0, 4, 8])
def test_one_frame_beyond_range_is_a_glitch_whose_rows_alone_are_flagged(start):
    short = synthesize_clip("random", 9, seed=3)
    xyz = bent_backwards(short.xyz, [start])
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(short), xyz)
    assert not verdict.flagged, verdict.reasons
    assert verdict.rows[start].all() and verdict.rows.sum(axis=1).tolist().count(0) == 8


@pytest.mark.parametrize("frames", [[0, 1], [4, 5], [7, 8], [1, 3, 5, 7], [0]])
def test_a_bend_that_holds_or_recurs_is_flagged(frames):
    short = synthesize_clip("random", 9, seed=3)
    xyz = bent_backwards(short.xyz, frames)
    sampling = "images" if frames == [0] else "video"
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(short), xyz, sampling=sampling)
    assert any("middle PIP" in reason for reason in verdict.reasons)
    assert verdict.rows[frames].all()


def test_a_single_frame_clip_is_judged_by_its_frame_alone(clip):
    bent = bent_backwards(clip.xyz[:1], [0])
    lengths = lengths_of(clip)
    assert assess(MEDIAPIPE, "mm", "right", lengths, bent).flagged
    assert not assess(MEDIAPIPE, "mm", "right", lengths, clip.xyz[:1]).flagged
    # repeated: scipy's mirrored running median of one frame reads memory beyond it
    for frame in (False, True):
        assert all(persistent_frames(np.array([frame])).tolist() == [frame]
                   for _ in range(50))


def test_a_clip_shorter_than_the_window_is_judged_frame_by_frame():
    for frames in ([True, False], [False, True], [True, True], [False, False]):
        assert persistent_frames(np.array(frames)).tolist() == frames
    assert persistent_frames(np.array([True, False, False])).tolist() == [False] * 3


def test_a_bone_that_stretches_is_flagged(clip):
    xyz = clip.xyz.copy()
    tip, dip = MEDIAPIPE.indices(["index_tip", "index_dip"])
    stretch = 1.0 + 0.8 * np.sin(np.arange(len(xyz)) / 3.0) ** 2
    xyz[:, tip] = xyz[:, dip] + (xyz[:, tip] - xyz[:, dip]) * stretch[:, None]
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(clip), xyz)
    assert any("index_tip changes length" in reason for reason in verdict.reasons)


def test_a_model_that_misses_its_markers_is_flagged(clip):
    residual = np.full(clip.xyz.shape[:2], 1.5)
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(clip), clip.xyz, residual)
    assert not verdict.flagged
    residual[: len(residual) // 2] = 25.0
    verdict = assess(MEDIAPIPE, "mm", "right", lengths_of(clip), clip.xyz, residual)
    assert any("does not fit the markers" in reason for reason in verdict.reasons)
    assert verdict.rows[0].all() and not verdict.rows[-1].any()


def test_units_are_respected(clip):
    lengths = lengths_of(clip) / 10.0
    assert not assess(MEDIAPIPE, "cm", "right", lengths, clip.xyz / 10.0).flagged
    assert assess(MEDIAPIPE, "mm", "right", lengths, None, n_frames=3).flagged


# --- joint order: a joint_map that swaps two fingers (issue 15) -----------------------------

def swapped(points, skeleton, first, second, parts=("mcp",)):
    out = points.copy()
    for part in parts:
        a, b = skeleton.index(f"{first}_{part}"), skeleton.index(f"{second}_{part}")
        out[:, [a, b]] = out[:, [b, a]]
    return out


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("motion", ["random", "clench", "rapid", "wave"])
def test_the_population_keeps_its_joint_order_in_3d_and_in_the_image(seed, motion):
    clip = synthesize_clip(motion, 120, seed=seed, hand="left" if seed % 2 else "right",
                           camera="pinhole" if seed % 3 == 0 else "orthographic")
    for points in (clip.xyz, clip.uv):
        reasons, rows = check_joint_order(MEDIAPIPE, points)
        assert reasons == [] and not rows.any()


def test_real_captures_keep_their_joint_order(dhg_mm, real_tools):
    assert check_joint_order(load_skeleton("dhg22"), dhg_mm)[0] == []
    doc = json.loads((real_tools / "interhand" / "test_interhand2.6m_joint_3d.json").read_text())
    hands = [np.array(frame["world_coord"])[first:first + 21][
        [INTERHAND_ORDER.index(j) for j in MEDIAPIPE.joints]]
        for frames in doc.values() for frame in frames.values()
        for first in (0, 21) if (np.array(frame["joint_valid"]).ravel()[first:first + 21]
                                 > 0).all()]
    assert len(hands) >= 4
    assert check_joint_order(MEDIAPIPE, np.stack(hands))[0] == []
    rows = [line.split(",") for line in
            (real_tools / "mediapipe" / "hand_landmarks.csv").read_text().splitlines()[1:]]
    for hand in ("0", "1"):
        points = np.array([[float(r[3]), float(r[4])] for r in rows if r[1] == hand])
        assert check_joint_order(MEDIAPIPE, points.reshape(-1, 21, 2))[0] == []


@pytest.mark.parametrize(("first", "second", "named"), [
    ("index", "ring", "ring_mcp, index_mcp"), ("middle", "ring", "ring_mcp, middle_mcp"),
    ("ring", "little", "little_mcp, ring_mcp"), ("index", "little", "little_mcp, index_mcp")])
def test_swapped_fingers_are_flagged_naming_them(clip, first, second, named):
    for points in (clip.xyz, clip.uv):
        wrong = swapped(points, MEDIAPIPE, first, second, ("mcp", "pip", "dip", "tip"))
        reasons, rows = check_joint_order(MEDIAPIPE, wrong)
        assert f"{named} look swapped: check the joint_map" in reasons[0]
        assert "out of order across the palm in 100% of frames" in reasons[0]
        assert rows[:, MEDIAPIPE.indices([f"{first}_mcp", f"{second}_mcp"])].all()


def test_index_and_little_swapped_put_the_thumb_on_the_wrong_side(clip):
    wrong = swapped(clip.xyz, MEDIAPIPE, "index", "little")
    reasons, _ = check_joint_order(MEDIAPIPE, wrong)
    assert "thumb_mcp lies nearer little_mcp than index_mcp" in reasons[-1]


def test_knuckles_at_one_point_or_missing_are_not_judged():
    points = np.zeros((3, MEDIAPIPE.n_joints, 3))
    points[1, :, 0] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reasons, rows = check_joint_order(MEDIAPIPE, points)
    assert reasons == [] and not rows.any()
