import numpy as np
import pytest

from handdb.errors import InputError
from handdb.hand.skeletons import load_skeleton
from handdb.ingest import dhg
from tests.unit.ingest.test_markers_csv import marker_spec

DHG22 = load_skeleton("dhg22")


def write(tmp_path, lines):
    path = tmp_path / "g.dhg.txt"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_one_line_a_frame_in_metres(tmp_path):
    world = np.random.default_rng(0).normal(0.0, 0.1, (4, 22, 3))
    path = write(tmp_path, [" ".join(f"{v:.6f}" for v in frame.ravel()) for frame in world])
    positions = dhg.read(path, marker_spec(skeleton="dhg22"), DHG22)
    assert positions.n_frames == 4 and positions.n_rows == 88
    np.testing.assert_allclose(positions.xyz.reshape(4, 22, 3), world * 1000.0, atol=1e-3)
    np.testing.assert_array_equal(positions.line[::22], [1, 2, 3, 4])


@pytest.mark.parametrize(("lines", "line", "field", "message"), [
    (["1 " * 66, "1 " * 65], 2, None, "has 65 fields, expected 66.*truncated"),
    (["1 " * 65 + "nan"], 1, "little_tip.z", "not a finite number"),
])
def test_bad_lines(tmp_path, lines, line, field, message):
    with pytest.raises(InputError, match=message) as info:
        dhg.read(write(tmp_path, lines), marker_spec(skeleton="dhg22"), DHG22)
    assert (info.value.line, info.value.field) == (line, field)
