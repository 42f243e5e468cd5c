"""Speed of synthetic clip generation: motion, forward kinematics and projection.

Prints frames per second of :func:`handdb.synthetic.synthesize_clip` for every motion and
camera, and of forward kinematics alone.

Run: ``.venv/bin/python benchmarks/synthetic.py [n_frames]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.hand.model import forward_kinematics  # noqa: E402
from handdb.synthetic import MOTIONS, make_hand, make_motion, model_poses, synthesize_clip  # noqa: E402


def frames_per_second(call, n_frames: int, repeats: int = 3) -> float:
    """Best of ``repeats`` runs of ``call()``, as frames per second."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return n_frames / best


def main(n_frames: int) -> None:
    for motion in MOTIONS:
        for camera in ("orthographic", "pinhole"):
            rate = frames_per_second(
                lambda m=motion, c=camera: synthesize_clip(m, n_frames, camera=c), n_frames)
            print(f"synthesize_clip {motion:>7} {camera:>12}: {rate:12,.0f} frames/s")
    model, motion = make_hand(), make_motion("random", n_frames)
    poses = model_poses(model, motion.angles, motion.root_rotation)
    rate = frames_per_second(lambda: forward_kinematics(model, poses), n_frames)
    print(f"forward_kinematics alone (21 joints):      {rate:12,.0f} frames/s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)
