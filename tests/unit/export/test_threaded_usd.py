"""Clips are exported from the build's worker threads: the first USD stages of a fresh
process, made by two threads at once, must not deadlock (USD loads its plugins then)."""

import subprocess
import sys

from tests.support.paths import REPO

#: Fresh processes tried; without the first stage made alone, about one in five hung.
N_PROCESSES = 10
#: Seconds one process may take (imports included; it takes 3-6 s here).
TIMEOUT_S = 60

RACE = """
import threading
from handdb.export.usd import export_clip_usd
from tests.support.motions import make_hinge_motion
from handdb.hand.skeletons import load_skeleton

motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=5)
start = threading.Barrier(2)

def export(name):
    start.wait()
    export_clip_usd(f"{sys.argv[1]}/{name}.usda", clip_id=name, skeleton=motion.skeleton,
                    xyz=motion.xyz, bone_lengths=motion.bone_lengths, fps=motion.fps,
                    units="mm", hand="right")

threads = [threading.Thread(target=export, args=(name,)) for name in ("a", "b")]
for thread in threads:
    thread.start()
for thread in threads:
    thread.join()
"""


def test_two_threads_making_a_fresh_process_first_stages_finish(tmp_path):
    for attempt in range(N_PROCESSES):
        folder = tmp_path / str(attempt)
        folder.mkdir()
        result = subprocess.run([sys.executable, "-c", f"import sys\n{RACE}", str(folder)],
                                cwd=REPO, capture_output=True, text=True, timeout=TIMEOUT_S)
        assert result.returncode == 0, result.stderr
        assert sorted(path.name for path in folder.iterdir()) == ["a.usda", "b.usda"]
