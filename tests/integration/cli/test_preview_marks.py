"""The build's thumbnail and ``handdb preview`` mark filled joints and show the truth."""

from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread
from PIL import Image
from typer.testing import CliRunner

from handdb.build import BuildOptions
from handdb.cli import app
from handdb.export.sheet import FILLED_RGB, TRUTH_RGB, preview_frames
from handdb.store.dataset import load_clip
from tests.support.building import build_demo_clips

#: A demo clip with occlusions filled, and one fully observed; both have ground truth.
GAPPY, COMPLETE = "rapid-occluded-s03", "rapid-s01"


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    return Path(build_demo_clips(tmp_path_factory.mktemp("marks"), (GAPPY, COMPLETE),
                                 BuildOptions()))


def _filled_in_sheet(db, clip_id):
    filled = load_clip(str(db), clip_id).filled.values
    return int(filled[preview_frames(len(filled))].sum())


def _count(image, rgb):
    return int((image == np.array(rgb)).all(axis=-1).sum())


def test_the_builds_thumbnail_marks_filled_joints_only_where_they_were_filled(db):
    assert _filled_in_sheet(db, GAPPY) > 0 and _filled_in_sheet(db, COMPLETE) == 0
    gappy, complete = (np.asarray(Image.open(db / "reports" / c / "preview.png").convert("RGB"))
                       for c in (GAPPY, COMPLETE))
    assert _count(gappy, FILLED_RGB) > 0
    assert _count(complete, FILLED_RGB) == 0
    assert _count(gappy, TRUTH_RGB) > 0 and _count(complete, TRUTH_RGB) > 0


def test_handdb_preview_marks_filled_joints_and_draws_the_truth(db, tmp_path):
    def magenta(clip_id):
        out = tmp_path / f"{clip_id}.png"
        result = CliRunner().invoke(app, ["preview", "--clip", clip_id, "--out", str(out),
                                          "--db", str(db)])
        assert result.exit_code == 0, result.output
        image = imread(out)
        return int(((image[..., 0] > 0.8) & (image[..., 1] < 0.35)
                    & (image[..., 2] > 0.8)).sum())

    assert magenta(GAPPY) > 20
    assert magenta(COMPLETE) == 0
