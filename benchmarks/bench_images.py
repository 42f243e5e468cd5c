"""CPU time of the per-clip images: the build's thumbnail, the labelled preview sheet (now
drawn on demand by ``handdb preview``) and the depth chart.

Synthesises ``rapid`` clips of the project's synthetic hand, draws each image a few times
after one warm-up (fonts, caches) and prints the best CPU time. With an output folder
given, the images are also kept there for a look.

Run: ``.venv/bin/python benchmarks/bench_images.py [out_folder]``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's handdb, before any installed copy

from handdb.export.preview import write_preview_png  # noqa: E402
from handdb.export.thumbnail import write_thumbnail_png  # noqa: E402
from handdb.hand.skeletons import load_skeleton  # noqa: E402
from handdb.synthetic import synthesize_clip  # noqa: E402
from handdb.validation.depth import comparison_chart, validation_table  # noqa: E402

CLIP_FRAMES = (300, 20_000)
REPEATS = 3
#: Depth noise of the fake estimates charted against the truth, clip units.
DEPTH_NOISE = (2.0, 5.0)
#: Share of the points marked filled in the thumbnail drawn as the build draws it.
FILLED_SHARE = 0.1


def best_cpu_seconds(run) -> float:
    """Run ``run()`` once to warm up, then ``REPEATS`` times; return the least CPU time."""
    run()
    times = []
    for _ in range(REPEATS):
        start = time.process_time()
        run()
        times.append(time.process_time() - start)
    return min(times)


def main(out: Path) -> None:
    rng = np.random.default_rng(0)
    for n_frames in CLIP_FRAMES:
        clip = synthesize_clip("rapid", n_frames, seed=0)
        skeleton = load_skeleton(clip.skeleton)
        preview = out / f"preview-{n_frames}.png"
        cpu = best_cpu_seconds(lambda: write_preview_png(  # noqa: B023
            preview, skeleton=skeleton, xyz=clip.xyz, units=clip.units,  # noqa: B023
            title=f"rapid, {n_frames} frames", fps=clip.fps))  # noqa: B023
        print(f"write_preview_png   {n_frames:>6d} frames  cpu {cpu:6.3f} s")
        thumbnail = out / f"thumbnail-{n_frames}.png"
        thumbnail_cpu = best_cpu_seconds(lambda: write_thumbnail_png(  # noqa: B023
            thumbnail, skeleton=skeleton, xyz=clip.xyz))  # noqa: B023
        print(f"write_thumbnail_png {n_frames:>6d} frames  cpu {thumbnail_cpu:6.3f} s "
              f"({thumbnail_cpu / cpu:.3f} of the sheet)")
        # as the build draws it: a tenth of the points filled, the truth beneath
        filled = rng.random(clip.xyz.shape[:2]) < FILLED_SHARE
        marked_cpu = best_cpu_seconds(lambda: write_thumbnail_png(  # noqa: B023
            thumbnail, skeleton=skeleton, xyz=clip.xyz, filled=filled,  # noqa: B023
            truth=clip.xyz + 5.0))  # noqa: B023
        print(f"  + filled and truth {n_frames:>6d} frames  cpu {marked_cpu:6.3f} s")

        noise = rng.normal(size=(len(DEPTH_NOISE), *clip.xyz.shape)) * np.array(DEPTH_NOISE)[
            :, None, None, None]
        estimates = {f"noise {sigma}": clip.xyz + n for sigma, n in zip(DEPTH_NOISE, noise,
                                                                         strict=True)}
        table = validation_table("bench", clip.xyz, estimates, skeleton, clip.units)
        chart = out / f"comparison-{n_frames}.png"
        cpu = best_cpu_seconds(lambda: chart.write_bytes(  # noqa: B023
            comparison_chart("bench", table, skeleton)))  # noqa: B023
        print(f"comparison_chart    {n_frames:>6d} frames  cpu {cpu:6.3f} s")


if __name__ == "__main__":
    if len(sys.argv) > 1:
        folder = Path(sys.argv[1])
        folder.mkdir(parents=True, exist_ok=True)
        main(folder)
    else:
        with tempfile.TemporaryDirectory() as scratch:
            main(Path(scratch))
