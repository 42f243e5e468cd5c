import json

import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import interhand
from tests.unit.ingest.test_markers_csv import SKELETON, marker_spec


def annotation(seed=0, valid=None):
    rng = np.random.default_rng(seed)
    coords = rng.normal(0.0, 50.0, (42, 3)) + [0.0, 0.0, 1000.0]
    flags = np.ones(42, dtype=bool) if valid is None else valid
    return {"world_coord": coords.tolist(), "joint_valid": [[bool(f)] for f in flags],
            "hand_type": "right", "hand_type_valid": True}


def read(tmp_path, doc, **spec):
    path = tmp_path / "ih.interhand.json"
    path.write_text(json.dumps(doc))
    return interhand.read(path, marker_spec(**spec), SKELETON)


def test_joints_follow_interhand_order_and_joint_valid(tmp_path):
    valid = np.ones(42, dtype=bool)
    valid[[3, 41]] = False
    doc = {"1": {"100": annotation(0, valid), "102": annotation(1)}}
    positions = read(tmp_path, doc, frame_offset="first", units="cm")
    assert positions.n_frames == 3
    first = positions.frame == 0
    assert SKELETON.index("thumb_cmc") not in positions.joint[first], "joint_valid 0"
    tip = first & (positions.joint == SKELETON.index("thumb_tip"))
    np.testing.assert_allclose(positions.xyz[tip][0], np.array(doc["1"]["100"]["world_coord"][0])
                               / 10.0)
    left = read(tmp_path, doc, frame_offset=99, hand="left")
    assert SKELETON.index("wrist") not in left.joint[left.frame == 1]
    np.testing.assert_array_equal(sorted(set(left.frame.tolist())), [1, 3])


@pytest.mark.parametrize(("doc", "spec", "field", "message"), [
    ({"1": {"a1": annotation()}}, {}, "1.a1", "is not a decimal number"),
    ({"1": {"5": annotation()}}, {"frame_offset": 9}, "1.5", "minus frame_offset 9 is negative"),
    ({"1": {"5000": annotation()}}, {}, "1.5000", 'add "frame_offset": "first"'),
    ({"1": {"2000000": annotation()}}, {"frame_offset": 1}, "1.2000000",
     "beyond handdb's limit"),
    ({"1": {"0": annotation() | {"joint_valid": [[2]] * 42}}}, {}, "1.0.joint_valid",
     "flags 0/1"),
    ({"1": {"0": annotation() | {"world_coord": [[1, 2]] * 42}}}, {}, "1.0.world_coord",
     "has shape 42 x 2"),
    ({"1": {"0": annotation(valid=np.zeros(42, dtype=bool))}}, {}, "1.joint_valid",
     "no valid right-hand joint"),
    ([1, 2], {}, None, "must be an object of captures"),
])
def test_broken_annotations_name_the_json_path(tmp_path, doc, spec, field, message):
    with pytest.raises(InputError, match=message) as info:
        read(tmp_path, doc, **spec)
    assert info.value.field == field
