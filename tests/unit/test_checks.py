"""The shared input checker: what the library's public functions accept."""

import numpy as np
import pytest

from handdb.checks import as_points, check_hand, mm_per_unit
from handdb.errors import ParameterError
from handdb.lifting import lift


def test_hands_and_units():
    assert check_hand("left") == "left"
    assert mm_per_unit("cm") == 10.0
    with pytest.raises(ParameterError, match="hand must be one of left, right, got 'Right'"):
        check_hand("Right")
    with pytest.raises(ParameterError, match="units must be one of mm, cm, m, in, got 'ft'"):
        mm_per_unit("ft")


@pytest.mark.parametrize("shape", [(4, 21, 2), (0, 21, 3), (21, 3)])
def test_point_arrays_of_the_wrong_shape_are_refused(shape):
    with pytest.raises(ParameterError, match=r"markers must be \(frames, 21, 3\), got shape"):
        as_points(np.zeros(shape), 21, 3, "markers")


def test_infinite_points_are_refused_and_nan_kept():
    points = np.zeros((2, 21, 3))
    points[0, 3] = np.nan
    np.testing.assert_array_equal(np.isnan(as_points(points, 21, 3, "xyz")),
                                  np.isnan(points))
    points[1, 4, 0] = np.inf
    with pytest.raises(ParameterError, match="infinite values; mark a missing point with NaN"):
        as_points(points, 21, 3, "xyz")


def test_library_entry_points_use_it(model):
    from handdb.markers.fit import fit_markers

    with pytest.raises(ParameterError, match="units must be one of"):
        fit_markers(np.zeros((3, 21, 3)), units="furlong")
    with pytest.raises(ParameterError, match="markers must be"):
        fit_markers(np.zeros((3, 20, 3)))
    with pytest.raises(ParameterError, match="hand must be one of"):
        lift(np.zeros((3, 21, 2)), model.skeleton, model.bone_length_array(),
             None, hand="both")
