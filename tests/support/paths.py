"""Where the repository and the shared real data are."""

from pathlib import Path

#: The repository's root.
REPO = Path(__file__).resolve().parents[2]

#: Real captures and tool outputs kept beside the repository (absent on some machines).
SHARED_DATA = REPO.parent / "shared" / "data"

#: The real DHG capture: 95 frames, 22 joints, metres.
DHG_SAMPLE = SHARED_DATA / "dhg-sample" / "skeletons_world.txt"

#: Real files from real tools.
REAL_TOOLS = SHARED_DATA / "real-tools"
