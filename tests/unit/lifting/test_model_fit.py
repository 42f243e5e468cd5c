import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.model import build_hand_model, forward_kinematics
from handdb.lifting import lift
from handdb.lifting.model_fit import METHOD, fit_2d
from tests.support.motions import smooth_poses

PINHOLE = Camera(model="pinhole", fx=500.0, fy=500.0, cx=320.0, cy=240.0)


@pytest.fixture(scope="module")
def scene():
    model = build_hand_model("right")
    truth = forward_kinematics(model, smooth_poses(model, 8, seed=41))
    lengths = np.full(model.n_joints, np.nan)
    lengths[model.skeleton.bones[:, 1]] = model.bone_lengths
    return model, truth, lengths


def pinhole_image(xyz):
    return np.stack([PINHOLE.fx * xyz[..., 0] / xyz[..., 2] + PINHOLE.cx,
                     PINHOLE.fy * xyz[..., 1] / xyz[..., 2] + PINHOLE.cy], axis=-1)


def root_relative(xyz):
    return xyz - xyz[:, :1]


def test_model_fit_recovers_depth_through_a_pinhole(scene):
    model, truth, lengths = scene
    uv = pinhole_image(truth)
    uv[np.random.default_rng(0).random(uv.shape[:2]) < 0.1] = np.nan
    result = fit_2d(uv, model.skeleton, lengths, PINHOLE)
    depth_error = np.abs(root_relative(result.xyz)[..., 2] - root_relative(truth)[..., 2])
    assert depth_error.mean() < 3.0
    assert np.abs(result.xyz[:, 0, 2] - truth[:, 0, 2]).mean() < 5.0
    assert result.method == METHOD
    assert np.isnan(result.scale).all()


def test_model_fit_is_a_registered_lifting_method(scene):
    model, truth, lengths = scene
    scale = 2.0
    uv = scale * truth[:3, :, :2]
    result = lift(uv, model.skeleton, lengths, Camera(), method=METHOD)
    assert result.xyz.shape == truth[:3].shape
    np.testing.assert_allclose(result.xyz[:, 0, 2], 0.0)
    np.testing.assert_allclose(result.scale, scale, rtol=0.05)
    reprojected = result.scale[:, None, None] * result.xyz[..., :2]
    assert np.abs(reprojected - uv).mean() < 1.0
