import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from handdb.clip import Camera
from handdb.errors import BoneLengthError
from handdb.hand.model import forward_kinematics
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting import available_methods, lift
from handdb.lifting.kinematic import MIRROR_SETTLED_ODDS
from handdb.synthetic.clips import synthesize_clip, thesis_clench_clip
from handdb.synthetic.hands import make_hand
from handdb.synthetic.kinematics import PALM_TO_CAMERA
from tests.unit.lifting.conftest import ORTHOGRAPHIC

#: Issue 4's targets (mm): mean root-relative |dZ|, bone-sign accuracy, pinhole |dZ|.
TARGET_DZ_MM = 5.0
TARGET_SIGN_ACCURACY = 0.95
TARGET_PINHOLE_DZ_MM = 10.0


def depth_error(result, truth, skeleton):
    root = skeleton.root
    est = result.xyz[..., 2] - result.xyz[:, root : root + 1, 2]
    true = truth[..., 2] - truth[:, root : root + 1, 2]
    return float(np.mean(np.abs(est - true)))


def sign_accuracy(result, truth, skeleton, threshold=5.0):
    parent, child = skeleton.bones.T
    true = truth[:, child, 2] - truth[:, parent, 2]
    est = result.xyz[:, child, 2] - result.xyz[:, parent, 2]
    counted = np.abs(true) >= threshold
    return float(np.mean(np.sign(true[counted]) == np.sign(est[counted])))


def synthetic(motion, camera="orthographic", seed=3, n_frames=400):
    clip = synthesize_clip(motion, n_frames, camera=camera, seed=seed)
    skeleton = load_skeleton(clip.skeleton)
    cam = Camera(**clip.camera) if camera == "pinhole" else ORTHOGRAPHIC
    return clip, skeleton, bone_length_array(skeleton, clip.bone_lengths), cam


def test_default_is_registered():
    assert {"kinematic", "thesis", "thesis-nocheck"} <= set(available_methods())


@pytest.mark.parametrize("motion", ["clench", "random"])
def test_default_recovers_truth_within_the_issue_targets(motion):
    clip, skeleton, lengths, camera = synthetic(motion)
    result = lift(clip.uv, skeleton, lengths, camera, hand=clip.hand)
    assert depth_error(result, clip.xyz, skeleton) <= TARGET_DZ_MM
    assert sign_accuracy(result, clip.xyz, skeleton) >= TARGET_SIGN_ACCURACY
    assert not result.mirror_ambiguous


def test_default_beats_the_thesis_on_rapid_gestures(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    ours = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, hand=clip.hand)
    thesis = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="thesis")
    assert depth_error(ours, clip.xyz, skeleton) < depth_error(thesis, clip.xyz, skeleton)
    assert sign_accuracy(ours, clip.xyz, skeleton) > sign_accuracy(thesis, clip.xyz, skeleton)


def test_rapid_gestures_meet_the_issue_targets(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    result = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, hand=clip.hand)
    assert depth_error(result, clip.xyz, skeleton) <= TARGET_DZ_MM
    assert sign_accuracy(result, clip.xyz, skeleton) >= TARGET_SIGN_ACCURACY


def test_rapid_gestures_through_a_pinhole_meet_the_issue_target():
    clip, skeleton, lengths, camera = synthetic("rapid", camera="pinhole", seed=1)
    result = lift(clip.uv, skeleton, lengths, camera, hand=clip.hand)
    assert depth_error(result, clip.xyz, skeleton) <= TARGET_PINHOLE_DZ_MM


def test_confidence_and_scale_are_well_formed(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    result = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, hand=clip.hand)
    bones = skeleton.bones[:, 1]
    assert np.all(np.isnan(result.sign_confidence[:, skeleton.root]))
    assert np.all((result.sign_confidence[:, bones] >= 0.5)
                  & (result.sign_confidence[:, bones] <= 1.0))
    assert np.all(result.length_inconsistency >= 0)
    np.testing.assert_allclose(result.scale, clip.scale, rtol=0.02)
    np.testing.assert_allclose(result.xyz[:, skeleton.root, 2], 0.0)


def test_pinhole_points_lie_on_their_rays_and_beat_flat():
    clip, skeleton, lengths, camera = synthetic("clench", camera="pinhole")
    result = lift(clip.uv, skeleton, lengths, camera, hand=clip.hand)
    assert np.all(np.isnan(result.scale))
    reprojected = result.xyz[..., :2] / result.xyz[..., 2:] * camera.fx + [camera.cx, camera.cy]
    np.testing.assert_allclose(reprojected, clip.uv, atol=1e-6)
    parent, child = skeleton.bones.T
    length = np.linalg.norm(result.xyz[:, child] - result.xyz[:, parent], axis=-1)
    real = result.length_inconsistency[:, child] == 0
    np.testing.assert_allclose(length[real], np.broadcast_to(lengths[child], length.shape)[real])
    flat = np.concatenate([clip.xyz[..., :2], np.zeros_like(clip.xyz[..., :1])], axis=-1)
    flat_error = np.mean(np.abs(flat[..., 2] - flat[:, :1, 2]
                                - (clip.xyz[..., 2] - clip.xyz[:, :1, 2])))
    assert depth_error(result, clip.xyz, skeleton) < 0.5 * flat_error


def tilted_flat_hand(n_frames=30):
    """A perfectly flat right hand (thumb too), turned 30-40° about the image y axis.

    A flat hand is its own mirror image, so no view can tell which way it tilts.
    """
    skeleton = load_skeleton("mediapipe21")
    model = make_hand("mediapipe21")
    flat = forward_kinematics(model, model.rest_pose()) * [1.0, 1.0, 0.0]
    parent, child = skeleton.bones.T
    lengths = np.full(skeleton.n_joints, np.nan)
    lengths[child] = np.linalg.norm(flat[child] - flat[parent], axis=-1)
    tilt = Rotation.from_euler("y", np.linspace(30, 40, n_frames)[:, None],
                               degrees=True).as_matrix()
    xyz = np.einsum("tij,jk,nk->tni", tilt, PALM_TO_CAMERA, flat)
    return skeleton, lengths, xyz


def test_mirror_ambiguity_is_reported_for_a_flat_hand():
    skeleton, lengths, xyz = tilted_flat_hand()
    result = lift(xyz[..., :2] * 2.0, skeleton, lengths, ORTHOGRAPHIC)
    assert result.mirror_ambiguous
    assert result.mirror_log_odds < np.log(MIRROR_SETTLED_ODDS)
    assert "mirror" in result.note
    bones = skeleton.bones[:, 1]
    np.testing.assert_allclose(result.sign_confidence[:, bones], 0.5, atol=0.05)


def test_mirror_is_settled_by_a_clenching_hand():
    clip, skeleton, lengths, camera = synthetic("clench")
    result = lift(clip.uv, skeleton, lengths, camera, hand=clip.hand)
    assert not result.mirror_ambiguous
    assert result.mirror_log_odds >= np.log(MIRROR_SETTLED_ODDS)
    thesis = lift(clip.uv, skeleton, lengths, camera, method="thesis", hand=clip.hand)
    assert thesis.mirror_log_odds is None


def test_inputs_are_never_mutated(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    uv = clip.uv.copy()
    uv[3, 5] = np.nan
    before_uv, before_lengths = uv.copy(), lengths.copy()
    for method in available_methods():
        lift(uv, skeleton, lengths, ORTHOGRAPHIC, method=method)
    np.testing.assert_array_equal(uv, before_uv)
    np.testing.assert_array_equal(lengths, before_lengths)


def test_missing_points_give_nan_below_them_only(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    uv = clip.uv.copy()
    pip = skeleton.index("index_pip")
    uv[10, pip] = np.nan
    result = lift(uv, skeleton, lengths, ORTHOGRAPHIC)
    missing = np.flatnonzero(np.isnan(result.xyz[10]).any(axis=-1))
    assert {skeleton.joints[j] for j in missing} == {"index_pip", "index_dip", "index_tip"}


def test_unknown_method_and_bad_shapes_are_refused(rapid_clip):
    clip, skeleton, lengths = rapid_clip
    with pytest.raises(ValueError, match="unknown lifting method"):
        lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="magic")
    with pytest.raises(ValueError, match="uv must be"):
        lift(clip.uv[..., :1], skeleton, lengths, ORTHOGRAPHIC)
    short = lengths.copy()
    short[skeleton.index("index_tip")] = np.nan
    with pytest.raises(BoneLengthError, match="index_tip"):
        lift(clip.uv, skeleton, short, ORTHOGRAPHIC)


def test_default_beats_the_thesis_on_its_own_clench_experiment():
    # the thesis's Table 4.1 experiment: thesis21, its appendix's lengths, palm to camera
    clip = thesis_clench_clip()
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    ours = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, hand=clip.hand)
    thesis = lift(clip.uv, skeleton, lengths, ORTHOGRAPHIC, method="thesis")
    assert depth_error(ours, clip.xyz, skeleton) < depth_error(thesis, clip.xyz, skeleton)
