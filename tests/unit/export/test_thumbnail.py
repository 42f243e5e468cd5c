import numpy as np
from matplotlib.colors import to_rgb
from PIL import Image

from handdb.export.sheet import FILLED_RGB, FINGER_COLOURS, FINGER_RGB, TRUTH_RGB, VIEWS
from handdb.export.thumbnail import (
    FILLED_PIXELS,
    GAP_PIXELS,
    PANEL_PIXELS,
    thumbnail_image,
    write_thumbnail_png,
)
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion


def test_thumbnail_colours_are_the_previews():
    for finger, name in FINGER_COLOURS.items():
        np.testing.assert_allclose(np.array(FINGER_RGB[finger]) / 255, to_rgb(name), atol=0.003)


def test_thumbnail_draws_every_panel_with_its_bones(tmp_path):
    skeleton = load_skeleton("mediapipe21")
    motion = make_hinge_motion(skeleton, n_frames=50)
    path = write_thumbnail_png(tmp_path / "clip.png", skeleton=skeleton, xyz=motion.xyz, count=4)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = np.asarray(Image.open(path).convert("RGB"))
    pitch = PANEL_PIXELS + GAP_PIXELS
    assert image.shape == (GAP_PIXELS + len(VIEWS) * pitch, GAP_PIXELS + 4 * pitch, 3)
    for row in range(len(VIEWS)):
        for column in range(4):
            top, left = GAP_PIXELS + row * pitch, GAP_PIXELS + column * pitch
            panel = image[top:top + PANEL_PIXELS, left:left + PANEL_PIXELS]
            for finger in ("thumb", "index", "little"):
                assert (panel == FINGER_RGB[finger]).all(axis=-1).sum() > 20, (row, column)
            assert (panel == 0).all(axis=-1).sum() >= 21 * 3   # the joints, in black


def test_missing_joints_leave_gaps():
    skeleton = load_skeleton("mediapipe21")
    xyz = make_hinge_motion(skeleton, n_frames=10).xyz
    thumb = [i for i, j in enumerate(skeleton.joints) if skeleton.fingers[i] == "thumb"]
    hidden = xyz.copy()
    hidden[:, thumb] = np.nan
    red = np.array(FINGER_RGB["thumb"])
    assert (thumbnail_image(skeleton, xyz, 3) == red).all(axis=-1).sum() > 50
    assert (thumbnail_image(skeleton, hidden, 3) == red).all(axis=-1).sum() == 0
    assert (thumbnail_image(skeleton, np.full_like(xyz, np.nan), 3) != 255).any()  # borders


def _count(image, rgb):
    return int((image == np.array(rgb)).all(axis=-1).sum())


def test_filled_joints_are_marked_only_where_points_were_filled():
    skeleton = load_skeleton("mediapipe21")
    xyz = make_hinge_motion(skeleton, n_frames=10).xyz
    filled = np.zeros(xyz.shape[:2], bool)
    filled[:, skeleton.index("index_tip")] = True
    marked = thumbnail_image(skeleton, xyz, 3, filled=filled)
    # one index tip a panel, a FILLED_PIXELS square (bones may cross it)
    pitch = PANEL_PIXELS + GAP_PIXELS
    for row in range(len(VIEWS)):
        for column in range(3):
            top, left = GAP_PIXELS + row * pitch, GAP_PIXELS + column * pitch
            panel = marked[top:top + PANEL_PIXELS, left:left + PANEL_PIXELS]
            assert 0 < _count(panel, FILLED_RGB) <= FILLED_PIXELS ** 2, (row, column)
    assert _count(thumbnail_image(skeleton, xyz, 3), FILLED_RGB) == 0
    assert _count(thumbnail_image(skeleton, xyz, 3, filled=np.zeros_like(filled)),
                  FILLED_RGB) == 0


def test_truth_is_drawn_faintly_root_on_root():
    skeleton = load_skeleton("mediapipe21")
    xyz = make_hinge_motion(skeleton, n_frames=10).xyz
    root = xyz[:, skeleton.root:skeleton.root + 1]
    # the truth: a larger hand, somewhere else (stored truth is not root-relative)
    truth = (xyz - root) * 1.15 + root + np.array([0.0, 0.0, 500.0])
    assert _count(thumbnail_image(skeleton, xyz, 3), TRUTH_RGB) == 0
    overlaid = thumbnail_image(skeleton, xyz, 3, truth=truth)
    assert _count(overlaid, TRUTH_RGB) > 100
    # root-aligned, the 500 mm offset does not push the truth out of the panels
    assert _count(overlaid, TRUTH_RGB) == _count(
        thumbnail_image(skeleton, xyz, 3, truth=truth - [0.0, 0.0, 500.0]), TRUTH_RGB)
    # the clip's own bones are drawn over the truth
    assert _count(overlaid, FINGER_RGB["thumb"]) == _count(thumbnail_image(skeleton, xyz, 3),
                                                           FINGER_RGB["thumb"])


def test_png_holds_the_drawn_pixels_in_a_palette(tmp_path):
    skeleton = load_skeleton("mediapipe21")
    motion = make_hinge_motion(skeleton, n_frames=30)
    filled = np.zeros(motion.xyz.shape[:2], bool)
    filled[::3, 8] = True
    root = motion.xyz[:, skeleton.root:skeleton.root + 1]
    truth = (motion.xyz - root) * 1.15 + root   # a larger hand, showing beneath
    path = write_thumbnail_png(tmp_path / "clip.png", skeleton=skeleton, xyz=motion.xyz,
                               count=4, filled=filled, truth=truth)
    with Image.open(path) as png:
        assert png.mode == "P"
        pixels = np.asarray(png.convert("RGB"))
    drawn = thumbnail_image(skeleton, motion.xyz, 4, filled=filled, truth=truth)
    assert np.array_equal(pixels, drawn)
    assert _count(drawn, FILLED_RGB) > 0 and _count(drawn, TRUTH_RGB) > 0
