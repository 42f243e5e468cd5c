from pathlib import Path

import numpy as np
import pytest

from handdb.hand.correspondence import convert_points
from handdb.hand.skeletons import load_skeleton
from handdb.markers.fit import fit_markers

DHG = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "dhg-sample"


@pytest.mark.slow
def test_real_capture_fits_within_its_own_length_noise():
    path = DHG / "skeletons_world.txt"
    if not path.is_file():
        pytest.skip("the DHG sample is not present")
    dhg = np.loadtxt(path).reshape(-1, 22, 3)[:30] * 1000.0
    markers = convert_points(dhg, load_skeleton("dhg22"), load_skeleton("mediapipe21"))
    fit = fit_markers(markers, hand="right")
    assert np.all(np.isfinite(fit.joints))
    assert np.nanmedian(fit.residual) < 12.0
