"""Reading speed of the track readers on large synthetic files.

Writes one long clip in each CSV-based format and the OpenPose folder format to a
temporary folder, reads each back with its reader and prints rows per second.

Run: ``.venv/bin/python benchmarks/readers.py [n_frames]``.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.hand.skeletons import load_skeleton  # noqa: E402
from handdb.ingest import dlc, maya, openpose, tracks_csv  # noqa: E402
from handdb.ingest.sidecar import parse_sidecar  # noqa: E402

SIDECAR = {"hand": "right", "fps": 30, "subject": "bench", "units": "mm",
           "camera": {"model": "orthographic"}}


def main(n_frames: int) -> None:
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        cases = []
        for name, module, skeleton_name, frames, options in [
            ("tracks_csv", tracks_csv, "mediapipe21", n_frames, {}),
            ("dlc", dlc, "mediapipe21", n_frames, {}),
            ("maya", maya, "thesis21", n_frames, {}),
            ("openpose", openpose, "mediapipe21", n_frames // 50, {"hand": "right"}),
        ]:
            skeleton = load_skeleton(skeleton_name)
            sidecar = root / f"{name}.clip.json"
            sidecar.write_text(json.dumps(SIDECAR | {"skeleton": skeleton_name}))
            path = root / f"{name}{module.FORMAT.suffix}"
            points = rng.uniform(0.0, 640.0, (frames, skeleton.n_joints, 3))
            if module is maya:
                module.write(path, points, skeleton)
            else:
                module.write(path, points[..., :2], rng.uniform(0, 1, points.shape[:2]),
                             skeleton, **options)
            cases.append((name, module, path, parse_sidecar(sidecar), skeleton))
        print(f"{'format':<12}{'rows':>10}{'seconds':>10}{'rows/s':>12}")
        for name, module, path, spec, skeleton in cases:
            start = time.perf_counter()
            rows = module.read(path, spec, skeleton).n_rows
            seconds = time.perf_counter() - start
            print(f"{name:<12}{rows:>10}{seconds:>10.2f}{rows / seconds:>12,.0f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50_000)
