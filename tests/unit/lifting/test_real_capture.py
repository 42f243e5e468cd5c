"""The default method on the real DHG capture: never worse than the thesis's method."""

import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import load_skeleton
from handdb.lifting import lift
from tests.support import real_data
from tests.unit.lifting.conftest import ORTHOGRAPHIC

PIXELS_PER_M = 1000.0
FOCAL_PX = 500.0
PRINCIPAL_POINT = np.array([320.0, 240.0])


def mean_depth_error(xyz, world, skeleton):
    root = skeleton.root
    estimate = xyz[..., 2] - xyz[:, root : root + 1, 2]
    truth = world[..., 2] - world[:, root : root + 1, 2]
    return float(np.mean(np.abs(estimate - truth)))


@pytest.mark.parametrize("view", ["orthographic", "pinhole"])
def test_default_is_no_worse_than_the_thesis_on_the_dhg_capture(dhg_world, view):
    skeleton = load_skeleton("dhg22")
    lengths = real_data.median_bone_lengths(dhg_world, skeleton)
    if view == "orthographic":
        uv, camera = dhg_world[..., :2] * PIXELS_PER_M, ORTHOGRAPHIC
    else:
        uv = dhg_world[..., :2] / dhg_world[..., 2:] * FOCAL_PX + PRINCIPAL_POINT
        camera = Camera("pinhole", FOCAL_PX, FOCAL_PX, *PRINCIPAL_POINT)
    errors = {method: mean_depth_error(lift(uv, skeleton, lengths, camera, method=method,
                                            hand="right").xyz, dhg_world, skeleton)
              for method in ("kinematic", "thesis")}
    assert errors["kinematic"] <= errors["thesis"]
