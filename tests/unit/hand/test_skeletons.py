import json

import numpy as np
import pytest

from handdb.errors import SkeletonError
from handdb.hand.skeletons import (
    SKELETONS_DIR,
    available_skeletons,
    convert_points,
    correspondence,
    load_skeleton,
)

MEDIAPIPE_ORDER = [
    "wrist", "thumb_cmc", "thumb_mcp", "thumb_ip", "thumb_tip",
    "index_mcp", "index_pip", "index_dip", "index_tip",
    "middle_mcp", "middle_pip", "middle_dip", "middle_tip",
    "ring_mcp", "ring_pip", "ring_dip", "ring_tip",
    "little_mcp", "little_pip", "little_dip", "little_tip",
]


def test_presets_are_shipped():
    assert {"mediapipe21", "thesis21", "dhg22"} <= set(available_skeletons())


@pytest.mark.parametrize("name", ["mediapipe21", "thesis21", "dhg22"])
def test_parents_come_before_children(name):
    skeleton = load_skeleton(name)
    for child, parent in enumerate(skeleton.parents):
        assert parent < child
    assert (skeleton.parents < 0).sum() == 1


def test_mediapipe21_is_the_canonical_marker_set():
    skeleton = load_skeleton("mediapipe21")
    assert list(skeleton.joints) == MEDIAPIPE_ORDER
    for finger in ("thumb", "index", "middle", "ring", "little"):
        chain = skeleton.finger_chain(finger)
        assert skeleton.joints[skeleton.parents[chain[0]]] == "wrist"
        assert all(skeleton.parents[b] == a for a, b in zip(chain, chain[1:], strict=False))
        assert skeleton.roles[chain[-1]] == "tip"


def test_thesis21_ids_follow_figure_4_4():
    skeleton = load_skeleton("thesis21")
    by_id = dict(zip(skeleton.ids, skeleton.joints, strict=True))
    assert by_id[20] == "palm_fold" and skeleton.root == skeleton.index("palm_fold")
    assert by_id[19] == "wrist"
    assert [by_id[i] for i in (0, 1, 2)] == ["thumb_tip", "thumb_ip", "thumb_mcp"]
    assert [by_id[i] for i in (3, 4, 5, 6)] == ["index_tip", "index_dip", "index_pip", "index_mcp"]
    assert [by_id[i] for i in (15, 16, 17, 18)] == [
        "little_tip", "little_dip", "little_pip", "little_mcp"]
    # every finger's MCP hangs from the palm fold, as in the appendix program
    for finger in ("thumb", "index", "middle", "ring", "little"):
        base = skeleton.finger_chain(finger)[0]
        assert skeleton.parents[base] == skeleton.root
    assert skeleton.reference_lengths["index_tip"] == pytest.approx(1.70821)
    assert set(skeleton.reference_lengths) == set(skeleton.bone_names)


def test_dhg22_names_map_to_the_dataset():
    skeleton = load_skeleton("dhg22")
    assert skeleton.n_joints == 22
    assert skeleton.source_names[:3] == ("wrist", "palm", "thumb_base")
    assert skeleton.source_names[skeleton.index("little_tip")] == "pinky_tip"


def test_unknown_skeleton_names_the_known_ones():
    with pytest.raises(SkeletonError, match="mediapipe21"):
        load_skeleton("openpose25")


def test_bad_topology_is_refused(tmp_path, monkeypatch):
    doc = json.loads((SKELETONS_DIR / "mediapipe21.json").read_text())
    doc["joints"][1]["parent"] = "thumb_tip"  # parent listed after the child
    (tmp_path / "broken.json").write_text(json.dumps(doc))
    monkeypatch.setattr("handdb.hand.skeletons.SKELETONS_DIR", tmp_path)
    load_skeleton.cache_clear()
    try:
        with pytest.raises(SkeletonError, match="listed before it"):
            load_skeleton("broken")
    finally:
        load_skeleton.cache_clear()


def test_convert_between_presets_by_name():
    mp, th, dhg = (load_skeleton(n) for n in ("mediapipe21", "thesis21", "dhg22"))
    rng = np.random.default_rng(0)
    points = rng.normal(size=(5, mp.n_joints, 3))
    as_thesis = convert_points(points, mp, th)
    assert as_thesis.shape == (5, 21, 3)
    assert np.isnan(as_thesis[:, th.index("palm_fold")]).all()
    np.testing.assert_array_equal(as_thesis[:, th.index("ring_dip")],
                                  points[:, mp.index("ring_dip")])
    back = convert_points(convert_points(points, mp, dhg), dhg, mp)
    np.testing.assert_array_equal(back, points)
    src, dst = correspondence(mp, th)
    assert len(src) == 20  # all but the thumb CMC


def test_convert_checks_the_joint_axis():
    mp, th = load_skeleton("mediapipe21"), load_skeleton("dhg22")
    with pytest.raises(ValueError, match="22 joints"):
        convert_points(np.zeros((2, 22, 3)), mp, th)


def test_a_shared_preset_cannot_be_edited():
    skeleton = load_skeleton("mediapipe21")
    with pytest.raises(ValueError, match="read-only"):
        skeleton.parents[1] = 5
    assert load_skeleton("mediapipe21").parents[1] == 0
