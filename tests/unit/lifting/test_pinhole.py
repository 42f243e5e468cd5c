import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting.pinhole import camera_rays, deepest_feasible_root, estimate_root_depth
from handdb.synthetic.clips import synthesize_clip


def pinhole_clip(motion):
    clip = synthesize_clip(motion, 120, camera="pinhole", seed=3)
    skeleton = load_skeleton(clip.skeleton)
    return clip, skeleton, bone_length_array(skeleton, clip.bone_lengths), Camera(**clip.camera)


@pytest.mark.parametrize("motion", ["rapid", "wave", "clench"])
def test_the_deepest_feasible_root_bounds_the_true_depth_tightly(motion):
    # noise-free tracks: the true pose fits the rays, so the bound is never shallower than
    # the truth; it is tight whenever some bone lies near the image plane
    clip, skeleton, lengths, camera = pinhole_clip(motion)
    truth = clip.xyz[:, skeleton.root, 2]
    guess = truth * np.linspace(0.8, 1.25, len(truth))          # a rough first guess
    bound = deepest_feasible_root(camera_rays(clip.uv, camera), guess, skeleton, lengths)
    ratio = bound / truth
    assert np.all(ratio > 0.999)
    assert np.median(ratio) < 1.01


def test_the_root_depth_follows_the_hand_within_a_percent():
    clip, skeleton, lengths, camera = pinhole_clip("rapid")
    truth = clip.xyz[:, skeleton.root, 2]
    weak_scale = np.full(len(truth), 0.5 * (camera.fx + camera.fy) / np.mean(truth) * 0.9)
    depth = estimate_root_depth(clip.uv, skeleton, lengths, camera, weak_scale)
    assert np.mean(np.abs(depth / truth - 1.0)) < 0.01


def test_a_missing_point_leaves_the_search_to_the_other_bones():
    clip, skeleton, lengths, camera = pinhole_clip("rapid")
    uv = clip.uv.copy()
    uv[:, skeleton.index("ring_tip")] = np.nan
    truth = clip.xyz[:, skeleton.root, 2]
    bound = deepest_feasible_root(camera_rays(uv, camera), truth, skeleton, lengths)
    assert np.all(np.isfinite(bound)) and np.all(bound / truth > 0.999)
