"""Frames that observe no point (a detector's dropped frames) are lifted without numpy's
``RuntimeWarning`` and leave every other frame placed."""

import warnings

import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.lifting import lift
from handdb.synthetic import synthesize_clip

EMPTY = np.r_[0:2, 30:33]


@pytest.mark.parametrize("camera", ["orthographic", "pinhole"])
def test_empty_frames_leave_the_others_placed_without_warnings(camera):
    clip = synthesize_clip("wave", 60, camera=camera, seed=1)
    skeleton = load_skeleton(clip.skeleton)
    uv = clip.uv.copy()
    uv[EMPTY] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        xyz = lift(uv, skeleton, bone_length_array(skeleton, clip.bone_lengths),
                   Camera(**clip.camera), hand=clip.hand).xyz
    kept = np.setdiff1d(np.arange(len(uv)), EMPTY)
    assert np.isfinite(xyz[kept]).all()
