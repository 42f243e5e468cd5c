"""The per-clip images are drawn from the build's worker threads: drawing several at once
must give the same pictures as drawing them one after another."""

from concurrent.futures import ThreadPoolExecutor
from io import BytesIO

import numpy as np
from matplotlib.image import imread

from handdb.export.preview import write_preview_png
from handdb.hand.skeletons import load_skeleton
from handdb.validation.depth import comparison_chart, validation_table
from tests.support.motions import make_hinge_motion

N_CLIPS = 4
WORKERS = 4
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def draw_clip_images(seed: int, folder) -> tuple[bytes, bytes]:
    """Preview and depth chart of one synthetic clip; returns both PNG files' content."""
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=60, seed=seed)
    noisy = motion.xyz + np.random.default_rng(seed).normal(scale=3.0, size=motion.xyz.shape)
    table = validation_table(f"clip-{seed}", motion.xyz, {"noisy": noisy}, motion.skeleton,
                             "mm")
    preview = write_preview_png(folder / f"clip-{seed}.png", skeleton=motion.skeleton,
                                xyz=motion.xyz, units="mm", title=f"clip-{seed}", fps=30.0)
    return preview.read_bytes(), comparison_chart(f"clip-{seed}", table, motion.skeleton)


def test_images_drawn_in_threads_match_images_drawn_in_turn(tmp_path):
    (tmp_path / "serial").mkdir()
    (tmp_path / "threads").mkdir()
    serial = [draw_clip_images(seed, tmp_path / "serial") for seed in range(N_CLIPS)]
    with ThreadPoolExecutor(WORKERS) as pool:
        threaded = list(pool.map(lambda seed: draw_clip_images(seed, tmp_path / "threads"),
                                 range(N_CLIPS)))

    for alone, together in zip(serial, threaded, strict=True):
        for png_alone, png_together in zip(alone, together, strict=True):
            assert png_together[:8] == PNG_SIGNATURE
            image = imread(BytesIO(png_together))
            assert (image[..., :3] < 0.9).any(axis=-1).mean() > 0.01
            np.testing.assert_array_equal(image, imread(BytesIO(png_alone)))
    previews = [imread(BytesIO(preview)) for preview, _ in threaded]
    assert not np.array_equal(previews[0], previews[1])
