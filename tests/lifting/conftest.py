from pathlib import Path

import numpy as np
import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.synthetic.clips import synthesize_clip

DHG_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "dhg-sample"


@pytest.fixture(scope="session")
def rapid_clip():
    """A 400-frame synthetic clip of rapid gestures, orthographic, mm."""
    clip = synthesize_clip("rapid", 400, camera="orthographic", seed=1)
    skeleton = load_skeleton(clip.skeleton)
    return clip, skeleton, bone_length_array(skeleton, clip.bone_lengths)


@pytest.fixture(scope="session")
def dhg_world():
    """The real DHG capture, ``(95, 22, 3)`` metres, or skip when it is absent."""
    path = DHG_DIR / "skeletons_world.txt"
    if not path.is_file():
        pytest.skip("DHG sample not available")
    return np.loadtxt(path).reshape(-1, 22, 3)


ORTHOGRAPHIC = Camera()
