import pytest

from handdb.clip import Camera
from handdb.hand.skeletons import bone_length_array, load_skeleton
from handdb.synthetic.clips import synthesize_clip


@pytest.fixture(scope="session")
def rapid_clip():
    """A 400-frame synthetic clip of rapid gestures, orthographic, mm."""
    clip = synthesize_clip("rapid", 400, camera="orthographic", seed=1)
    skeleton = load_skeleton(clip.skeleton)
    return clip, skeleton, bone_length_array(skeleton, clip.bone_lengths)


ORTHOGRAPHIC = Camera()
