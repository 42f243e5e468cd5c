import numpy as np

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting import lift
from handdb.synthetic.clips import synthesize_clip


def acceleration_energy(xyz):
    return float(np.sum((xyz[2:] - 2 * xyz[1:-1] + xyz[:-2]) ** 2))


def test_refinement_keeps_image_points_and_smooths_noisy_tracks():
    clip = synthesize_clip("clench", 40, camera="orthographic", seed=5, noise_px=1.5)
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    seed = lift(clip.uv, skeleton, lengths, Camera())
    refined = lift(clip.uv, skeleton, lengths, Camera(), method="kinematic-refined")
    assert refined.method == "kinematic-refined"
    np.testing.assert_allclose(refined.xyz[..., :2], seed.xyz[..., :2])
    np.testing.assert_allclose(refined.xyz[:, skeleton.root, 2], 0.0, atol=1e-9)
    assert acceleration_energy(refined.xyz) < acceleration_energy(seed.xyz)


def test_pinhole_refinement_stays_on_the_rays():
    clip = synthesize_clip("clench", 20, camera="pinhole", seed=5, noise_px=1.0)
    skeleton = load_skeleton(clip.skeleton)
    lengths = bone_length_array(skeleton, clip.bone_lengths)
    camera = Camera(**clip.camera)
    refined = lift(clip.uv, skeleton, lengths, camera, method="kinematic-refined")
    reprojected = refined.xyz[..., :2] / refined.xyz[..., 2:] * camera.fx + [camera.cx,
                                                                             camera.cy]
    np.testing.assert_allclose(reprojected, clip.uv, atol=1e-6)
