import numpy as np
import pytest

from handdb.errors import InputError
from handdb.ingest import qtm
from handdb.ingest.registry import match_format
from tests.unit.ingest.test_markers_csv import SKELETON, marker_spec

NAMES = ("wrist", "index_tip", "elbow")


def qtm_text(rows, *, frames=None, header=None, names=NAMES, columns=True):
    """A QTM 3D export: header lines, the column header and ``rows`` (lists of cells)."""
    keys = header or {"NO_OF_FRAMES": str(len(rows) if frames is None else frames),
                      "NO_OF_CAMERAS": "7", "NO_OF_MARKERS": str(len(names)),
                      "FREQUENCY": "100", "DATA_INCLUDED": "3D",
                      "MARKER_NAMES": "\t".join(names),
                      "TRAJECTORY_TYPES": "\t".join(["Measured"] * len(names))}
    lines = [f"{key}\t{value}" for key, value in keys.items()]
    if columns:
        lines.append("\t".join(["Frame", "Time"] + [f"{n} {a}" for n in names
                                                    for a in "XYZ"]) + "\t")
    lines += ["\t".join(map(str, row)) for row in rows]
    return "\r\n".join(lines) + "\r\n"


def row(frame, *values):
    return [frame, f"{(frame - 1) / 100:.5f}", *values]


GOOD = [row(1, 1, 2, 3, 4, 5, 6, 7, 8, 9), row(2, "nan", "nan", "nan", 4, 5, 6, 7, 8, 9),
        row(3, 1.5, 2, 3, "NULL", "NULL", "NULL", 7, 8, 9)]


def read(tmp_path, text, **spec):
    path = tmp_path / "m01.qtm.tsv"
    path.write_text(text)
    return qtm.read(path, marker_spec(fps=100.0, joint_map={"elbow": None}) if not spec
                    else marker_spec(**{"fps": 100.0} | spec), SKELETON)


def test_markers_nan_triplets_and_units(tmp_path):
    positions = read(tmp_path, qtm_text(GOOD), units="cm", joint_map={"elbow": None})
    assert match_format(tmp_path / "m01.qtm.tsv")[0].name == "qtm"
    assert positions.n_frames == 3 and positions.names == frozenset(NAMES)
    wrist = positions.joint == SKELETON.index("wrist")
    np.testing.assert_array_equal(positions.frame[wrist], [0, 2])
    np.testing.assert_allclose(positions.xyz[wrist], [[0.1, 0.2, 0.3], [0.15, 0.2, 0.3]])
    np.testing.assert_array_equal(positions.line[wrist], [9, 11])
    assert SKELETON.index("index_tip") in positions.joint


def test_without_the_column_header_frames_count_rows(tmp_path):
    rows = [r[2:] for r in GOOD]
    positions = read(tmp_path, qtm_text(rows, columns=False))
    assert sorted(set(positions.frame.tolist())) == [0, 1, 2]


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    (qtm_text(GOOD, frames=5), 11, "NO_OF_FRAMES", "has 3 data rows, but NO_OF_FRAMES says 5: "
     "the file is truncated"),
    (qtm_text(GOOD)[:-12], 11, None, "has 8 fields, expected 11.*truncated"),
    (qtm_text([row(1, 1, 2, 3, 4, "nan", 6, 7, 8, 9)]), 9, "index_tip Y",
     "all three cells nan"),
    (qtm_text([row(1, "110,406", 2, 3, 4, 5, 6, 7, 8, 9)]), 9, "wrist X", "decimal comma"),
    (qtm_text([row(1, *range(9)), row(3, *range(9))]), 10, "Frame", "frame 3 follows frame 1"),
    (qtm_text(GOOD).replace("DATA_INCLUDED\t3D", "DATA_INCLUDED\t2D"), 5, "DATA_INCLUDED",
     "holds 2D data; export 3D"),
    (qtm_text(GOOD).replace("NO_OF_MARKERS\t3", "NO_OF_MARKERS\t4"), 6, "MARKER_NAMES",
     "names 3 markers, but NO_OF_MARKERS says 4"),
    (qtm_text(GOOD).replace("FREQUENCY\t100", "FREQUENCY\tEXT"), 4, "FREQUENCY",
     "must be a frame rate"),
    (qtm_text(GOOD).replace("elbow X", "elbow x"), 8, "elbow X", "expected 'elbow X'"),
    (qtm_text(GOOD).replace("elbow Z\t", "elbow Z\tbattery\t"), 8, "Frame",
     "column 12 is 'battery', expected no column after 'elbow Z'"),
    (qtm_text(GOOD).replace("\telbow Z\t", "\t"), 8, "elbow Z",
     "column 11 is missing, expected 'elbow Z'"),
    (qtm_text(GOOD, names=("wrist", "wrist", "elbow")), 6, "MARKER_NAMES", "named twice"),
    (qtm_text(GOOD).replace("MARKER_NAMES", "MARKERS"), 1, "MARKER_NAMES",
     "no MARKER_NAMES line"),
    (qtm_text(GOOD).replace("NO_OF_CAMERAS\t7", "NO_OF_FRAMES\t3"), 2, "NO_OF_FRAMES",
     "given twice"),
])
def test_broken_exports_name_line_and_field(tmp_path, text, line, field, message):
    with pytest.raises(InputError, match=message) as info:
        read(tmp_path, text)
    assert (info.value.line, info.value.field) == (line, field)
    assert info.value.file.endswith("m01.qtm.tsv")


def test_frequency_must_be_the_sidecar_fps(tmp_path):
    with pytest.raises(InputError, match='FREQUENCY 100 Hz; set "fps": 100') as info:
        read(tmp_path, qtm_text(GOOD), fps=120.0, joint_map={"elbow": None})
    assert (info.value.file, info.value.field) == ("m01.clip.json", "fps")
