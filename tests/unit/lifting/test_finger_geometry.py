import numpy as np

from handdb.clip import Camera
from handdb.hand.layout import hand_layout
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting.finger_geometry import perspective_candidates
from handdb.lifting.pinhole import camera_rays, ray_roots, walk_rays
from handdb.synthetic.clips import synthesize_clip


def test_ray_roots_lie_on_the_ray_at_the_bone_length():
    origin = np.array([[10.0, -5.0, 300.0]])
    ray = np.array([[0.05, 0.02, 1.0]])
    far, near, excess = ray_roots(origin, ray, 40.0)
    for point in (far, near):
        np.testing.assert_allclose(np.linalg.norm(point - origin), 40.0)
        np.testing.assert_allclose(np.cross(point, ray), 0.0, atol=1e-9)
    assert far[0, 2] > near[0, 2] and excess[0] == 0.0
    _, _, missed = ray_roots(origin, np.array([[1.0, 1.0, 1.0]]), 40.0)
    assert missed[0] > 0.0


def test_walk_with_true_depths_reproduces_the_pinhole_truth():
    clip = synthesize_clip("clench", 30, camera="pinhole", seed=2)
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    camera = Camera(**clip.camera)
    parent, child = skeleton.bones.T
    bone_dz = np.full(clip.xyz.shape[:2], np.nan)
    bone_dz[:, child] = clip.xyz[:, child, 2] - clip.xyz[:, parent, 2]
    xyz, excess = walk_rays(camera_rays(clip.uv, camera), clip.xyz[:, skeleton.root, 2],
                            skeleton, lengths, bone_dz)
    np.testing.assert_allclose(xyz, clip.xyz, atol=1e-6)
    assert np.all(excess < 1e-6)


def test_perspective_candidates_contain_the_true_pose():
    clip = synthesize_clip("clench", 30, camera="pinhole", seed=2)
    skeleton = load_skeleton(clip.skeleton)
    layout = hand_layout(skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    palm = np.stack([clip.xyz, clip.xyz], axis=1)
    candidates = perspective_candidates(camera_rays(clip.uv, Camera(**clip.camera)), palm,
                                        lengths, layout)
    first, second, third = candidates.joints
    truth = clip.xyz[:, layout.chains]                                   # (T, F, 3, 3)
    nearest = np.min(np.linalg.norm(third[:, 0] - truth[:, :, None, None, None, 2], axis=-1),
                     axis=(-3, -2, -1))
    np.testing.assert_allclose(nearest, 0.0, atol=1e-6)
    assert first.shape[-2:] == (2, 3) and second.shape[-3:] == (2, 2, 3)
