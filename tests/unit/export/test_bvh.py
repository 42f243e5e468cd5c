import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.clip import METERS_PER_UNIT
from handdb.export.bvh import export_clip_bvh
from handdb.export.rotations import CAMERA_TO_Y_UP
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion


def parse_bvh(text):
    """A small independent BVH reader: joints (name, parent, offset, channels) and motion."""
    tokens = text.split()
    joints, stack, i = [], [], 0
    while tokens[i] != "MOTION":
        token = tokens[i]
        if token in ("ROOT", "JOINT"):
            joints.append({"name": tokens[i + 1], "parent": stack[-1] if stack else None,
                           "channels": []})
            i += 2
        elif token == "End":
            joints.append({"name": None, "parent": stack[-1], "channels": []})
            i += 2
        elif token == "{":
            stack.append(len(joints) - 1)
            i += 1
        elif token == "}":
            stack.pop()
            i += 1
        elif token == "OFFSET":
            joints[stack[-1]]["offset"] = np.array(tokens[i + 1:i + 4], dtype=float)
            i += 4
        elif token == "CHANNELS":
            n = int(tokens[i + 1])
            joints[stack[-1]]["channels"] = tokens[i + 2:i + 2 + n]
            i += 2 + n
        else:
            i += 1
    n_frames = int(tokens[i + 2])
    frame_time = float(tokens[i + 5])
    values = np.array(tokens[i + 6:], dtype=float).reshape(n_frames, -1)
    return joints, frame_time, values


def bvh_positions(joints, values):
    """World positions of the named joints by forward kinematics, ``{name: (T, 3)}``."""
    n_frames = len(values)
    orientation, position, column = {}, {}, 0
    for index, joint in enumerate(joints):
        channels = joint["channels"]
        data = values[:, column:column + len(channels)]
        column += len(channels)
        translation = np.tile(joint["offset"], (n_frames, 1))
        rotation = Rotation.identity(n_frames)
        if channels:
            named = dict(zip(channels, data.T, strict=True))
            if "Xposition" in named:
                translation = np.stack([named[f"{a}position"] for a in "XYZ"], axis=1)
            axes = "".join(c[0] for c in channels if c.endswith("rotation"))
            rotation = Rotation.from_euler(axes, np.stack([named[f"{a}rotation"] for a in axes],
                                                          axis=1), degrees=True)
        parent = joint["parent"]
        if parent is None:
            orientation[index], position[index] = rotation, translation
        else:
            orientation[index] = orientation[parent] * rotation
            position[index] = position[parent] + orientation[parent].apply(translation)
    return {j["name"]: position[i] for i, j in enumerate(joints) if j["name"]}


@pytest.mark.parametrize(("name", "units"), [("mediapipe21", "mm"), ("thesis21", "cm"),
                                             ("dhg22", "m")])
def test_bvh_round_trip_reproduces_the_joints_in_metres(tmp_path, name, units):
    """The file is in metres whatever the clip's units (the clip's numbers read as ``units``)."""
    motion = make_hinge_motion(load_skeleton(name), n_frames=30)
    path = export_clip_bvh(tmp_path / "clip.bvh", skeleton=motion.skeleton, xyz=motion.xyz,
                           bone_lengths=motion.bone_lengths, fps=motion.fps, units=units)
    joints, frame_time, values = parse_bvh(path.read_text())
    assert frame_time == pytest.approx(1 / motion.fps)
    assert len(values) == len(motion.xyz)
    positions = bvh_positions(joints, values)
    assert set(positions) == set(motion.skeleton.joints)
    metres = METERS_PER_UNIT[units]
    tolerance = 1e-4 * motion.bone_lengths[motion.bone_lengths > 0].min() * metres
    for j, joint in enumerate(motion.skeleton.joints):
        expected = metres * CAMERA_TO_Y_UP.apply(motion.xyz[:, j])
        assert np.abs(positions[joint] - expected).max() < tolerance, joint


def test_finger_offsets_are_bone_lengths_and_hinges_use_one_channel(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=30)
    skeleton = motion.skeleton
    path = export_clip_bvh(tmp_path / "clip.bvh", skeleton=skeleton, xyz=motion.xyz,
                           bone_lengths=motion.bone_lengths, fps=motion.fps, units="mm")
    joints, _, values = parse_bvh(path.read_text())
    named = {j["name"]: j for j in joints if j["name"]}
    pip = named["index_pip"]
    pip_length = motion.bone_lengths[skeleton.index("index_pip")]
    np.testing.assert_allclose(pip["offset"], [0, 1e-3 * pip_length, 0], atol=1e-9)
    assert pip["channels"] == ["Xrotation", "Zrotation", "Yrotation"]
    assert named["index_mcp"]["channels"][:3] == ["Xposition", "Yposition", "Zposition"]
    start = sum(len(j["channels"]) for j in joints[:joints.index(pip)])
    flexion, abduction, twist = values[:, start:start + 3].T
    assert flexion.min() > 14.0
    np.testing.assert_allclose([abduction, twist], 0.0, atol=1e-5)
