from pathlib import Path

import numpy as np
import pytest

from handdb.skeletons import load_skeleton
from handdb.synthetic.clips import synthesize_clip

DHG_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "dhg-sample"

#: DHG positions are metres; the tests read them as 1 pixel = 1 mm.
MM_PER_M = 1000.0


@pytest.fixture(scope="session")
def mediapipe():
    return load_skeleton("mediapipe21")


@pytest.fixture(scope="session")
def thesis21():
    return load_skeleton("thesis21")


@pytest.fixture(scope="session")
def rapid_clip():
    return synthesize_clip("rapid", 400, seed=3)


@pytest.fixture(scope="session")
def dhg_xyz():
    path = DHG_DIR / "skeletons_world.txt"
    if not path.is_file():
        pytest.skip(f"real capture not available at {DHG_DIR}")
    return np.loadtxt(path).reshape(-1, 22, 3) * MM_PER_M
