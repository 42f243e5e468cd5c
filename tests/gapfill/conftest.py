from pathlib import Path

import numpy as np
import pytest

from handdb.hand.skeletons import load_skeleton
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


#: Demo clips put in the test database: one with complete tracks, one with gaps.
DEMO_DB_CLIPS = ("rapid-s01", "wave-s02")


@pytest.fixture(scope="session")
def demo_db(tmp_path_factory):
    """A database holding two demo clips, built in this process (no orchestrator)."""
    from handdb.build import BuildOptions, build_in_process
    from handdb.demo import write_demo_inbox

    root = tmp_path_factory.mktemp("gapfill-db")
    demo, inbox = root / "demo", root / "inbox"
    write_demo_inbox(demo)
    inbox.mkdir()
    for clip_id in DEMO_DB_CLIPS:
        for path in demo.glob(f"{clip_id}.*"):
            path.rename(inbox / path.name)
    db = str(root / "db")
    summary = build_in_process(inbox, db, BuildOptions(export_usd=False))
    assert sorted(summary.processed) == sorted(DEMO_DB_CLIPS)
    return db
