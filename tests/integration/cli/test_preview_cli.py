"""``handdb preview`` draws the labelled contact sheet of a stored clip on demand."""

import numpy as np
from matplotlib.image import imread
from typer.testing import CliRunner

from handdb.cli import app
from handdb.hand.skeletons import load_skeleton
from tests.integration.cli.test_export_cli import CLIP_ID, write_database
from tests.support.motions import make_hinge_motion


def test_preview_draws_the_stored_clip(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=24, seed=7)
    db = write_database(tmp_path / "db", motion)
    out = tmp_path / "sheet.png"
    result = CliRunner().invoke(app, ["preview", "--clip", CLIP_ID, "--out", str(out),
                                      "--db", db, "--frames", "3"])
    assert result.exit_code == 0, result.output
    assert result.output.strip() == str(out)
    image = imread(out)
    assert image.shape[1] > image.shape[0] > 300
    red = (image[..., 0] > 0.7) & (image[..., 1] < 0.3) & (image[..., 2] < 0.3)
    assert red.sum() > 100   # the thumb's bones
    assert 0.02 < (image[..., :3] < 0.9).any(axis=-1).mean() < 0.5


def test_preview_reports_an_unknown_clip_and_a_wrong_suffix(tmp_path):
    motion = make_hinge_motion(load_skeleton("mediapipe21"), n_frames=5)
    db = write_database(tmp_path / "db", motion)
    result = CliRunner().invoke(app, ["preview", "--clip", "nope", "--out",
                                      str(tmp_path / "x.png"), "--db", db])
    assert result.exit_code == 1 and "nope" in result.output
    result = CliRunner().invoke(app, ["preview", "--clip", CLIP_ID, "--out",
                                      str(tmp_path / "x.jpg"), "--db", db])
    assert result.exit_code == 2 and not np.any([p.suffix == ".jpg" for p in tmp_path.iterdir()])
