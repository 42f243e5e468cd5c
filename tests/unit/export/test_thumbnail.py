import numpy as np
from matplotlib.colors import to_rgb
from PIL import Image

from handdb.export.sheet import FINGER_COLOURS, FINGER_RGB, VIEWS
from handdb.export.thumbnail import GAP_PIXELS, PANEL_PIXELS, thumbnail_image, write_thumbnail_png
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
