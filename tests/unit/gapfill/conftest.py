import pytest

from handdb.hand.skeletons import load_skeleton
from handdb.synthetic.clips import synthesize_clip


@pytest.fixture(scope="session")
def mediapipe():
    return load_skeleton("mediapipe21")


@pytest.fixture(scope="session")
def thesis21():
    return load_skeleton("thesis21")


@pytest.fixture(scope="session")
def rapid_clip():
    return synthesize_clip("rapid", 400, seed=3)
