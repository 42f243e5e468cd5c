import numpy as np
import pytest

from handdb.hand.skeletons import load_skeleton
from handdb.markers.fit import fit_markers


@pytest.mark.slow
def test_real_capture_fits_within_its_own_length_noise(dhg_mm):
    dhg, mediapipe = load_skeleton("dhg22"), load_skeleton("mediapipe21")
    markers = dhg_mm[:30, dhg.indices(mediapipe.joints)]
    fit = fit_markers(markers, hand="right")
    assert np.all(np.isfinite(fit.joints))
    assert np.nanmedian(fit.residual) < 12.0
