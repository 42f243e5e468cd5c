"""Export clips of the project's synthetic hand (handdb.synthetic), an independent model."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.export.rotations import (
    CAMERA_TO_Y_UP,
    joint_rotations,
    motion_positions,
)
from handdb.export.usd import export_clip_usd
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.synthetic import synthesize_clip
from tests.support.usd_reading import joint_world_positions, open_skeleton

#: Largest turn of a hinge about an axis other than its own: the synthetic fingers bend
#: about slightly converging axes, and a nearly straight finger's axis is the palm's.
HINGE_OFF_AXIS = np.deg2rad(1.0)


@pytest.fixture(params=[("mediapipe21", "right"), ("thesis21", "left"), ("dhg22", "left")],
                ids=lambda p: "-".join(p))
def clip(request):
    skeleton, hand = request.param
    return synthesize_clip("rapid", 90, skeleton=skeleton, hand=hand, seed=4)


def test_rotations_of_the_synthetic_hand(clip):
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    motion = joint_rotations(clip.xyz, skeleton, lengths)
    np.testing.assert_allclose(motion_positions(motion, skeleton), clip.xyz, atol=1e-9)
    hinges = [j for j, role in enumerate(skeleton.roles) if role in ("pip", "dip", "ip")]
    rotvec = Rotation.from_quat(motion.rotations[:, hinges].reshape(-1, 4),
                                scalar_first=True).as_rotvec()
    assert np.abs(rotvec[:, 1:]).max() < HINGE_OFF_AXIS
    assert np.rad2deg(np.abs(rotvec[:, 0])).max() > 45


def test_usd_round_trip_of_the_synthetic_hand(clip, tmp_path):
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    path = export_clip_usd(tmp_path / "clip.usdc", clip_id="synthetic", skeleton=skeleton,
                           xyz=clip.xyz, bone_lengths=lengths, fps=clip.fps, units=clip.units,
                           hand=clip.hand)
    opened = open_skeleton(path)
    stage_xyz = joint_world_positions(opened, len(clip.xyz))
    expected = CAMERA_TO_Y_UP.apply(clip.xyz.reshape(-1, 3)).reshape(clip.xyz.shape)
    assert np.abs(stage_xyz - expected).max() < 1e-4 * lengths[lengths > 0].min()
