import numpy as np
from matplotlib.image import imread

from handdb.export.preview import preview_frames, write_preview_png
from handdb.hand.skeletons import load_skeleton
from tests.support.motions import make_hinge_motion


def test_preview_frames_span_the_clip():
    np.testing.assert_array_equal(preview_frames(101, 5), [0, 25, 50, 75, 100])
    np.testing.assert_array_equal(preview_frames(3, 6), [0, 1, 2])


def test_contact_sheet_draws_the_hand(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=50)
    xyz = motion.xyz.copy()
    xyz[10:20, 4] = np.nan
    path = write_preview_png(tmp_path / "clip.png", skeleton=motion.skeleton, xyz=xyz,
                             units="mm", title="clip-01", fps=30.0, count=4)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    image = imread(path)
    assert image.shape[1] > image.shape[0] > 300
    inked = (image[..., :3] < 0.9).any(axis=-1).mean()
    assert 0.02 < inked < 0.5
    red = (image[..., 0] > 0.7) & (image[..., 1] < 0.3) & (image[..., 2] < 0.3)
    assert red.sum() > 100


def _magenta(image):
    return int(((image[..., 0] > 0.8) & (image[..., 1] < 0.35) & (image[..., 2] > 0.8)).sum())


def _truth_grey(image):
    rgb = image[..., :3]
    return int((np.abs(rgb - 0.8) < 0.03).all(axis=-1).sum())


def test_contact_sheet_marks_filled_joints_and_overlays_truth(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=50)
    skeleton, xyz = motion.skeleton, motion.xyz
    filled = np.zeros(xyz.shape[:2], bool)
    filled[:, skeleton.index("index_tip")] = True
    root = xyz[:, skeleton.root:skeleton.root + 1]
    truth = (xyz - root) * 1.15 + root + np.array([0.0, 0.0, 300.0])

    def sheet(name, **extra):
        return imread(write_preview_png(tmp_path / name, skeleton=skeleton, xyz=xyz,
                                        units="mm", count=4, **extra))

    plain, marked = sheet("plain.png"), sheet("marked.png", filled=filled, truth=truth)
    assert _magenta(plain) == 0
    assert _magenta(marked) > 8 * 10          # a ring at each of 8 panels, and the legend
    assert _truth_grey(marked) > 3 * _truth_grey(plain) > 0  # antialiasing greys a few
    assert _magenta(sheet("none.png", filled=np.zeros_like(filled))) == 0
