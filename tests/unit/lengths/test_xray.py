from pathlib import Path

import pytest

from handdb.errors import InputError
from handdb.ingest.xray import read_xray

HEADER = "image_id,finger,segment,length,subject,sex,age,side\n"


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "hands.xray.csv"
    path.write_text(text)
    return path


def _finger_rows(image: str, finger: str, lengths: tuple[float, ...], meta: str = "") -> str:
    return "".join(f"{image},{finger},J{k + 1},{v},{meta}\n" for k, v in enumerate(lengths))


def test_reads_complete_images_with_metadata(tmp_path):
    text = HEADER + _finger_rows("x1", "index", (40.0, 22.0, 18.0), "s1,F,34,right") \
        + _finger_rows("x1", "thumb", (30.0, 25.0), "s1,F,34,right")
    table, refused = read_xray(_write(tmp_path, text))
    assert refused == []
    assert table.num_rows == 5
    rows = table.to_pylist()
    assert {r["finger"] for r in rows} == {"index", "thumb"}
    assert rows[0]["sex"] == "f" and rows[0]["age"] == 34.0 and rows[0]["side"] == "right"
    assert rows[0]["line"] >= 2 and rows[0]["source_file"] == "hands.xray.csv"


def test_missing_segment_quarantines_only_that_finger(tmp_path):
    text = (HEADER + _finger_rows("x1", "index", (40.0, 22.0))
            + _finger_rows("x1", "middle", (45.0, 27.0, 20.0)))
    table, refused = read_xray(_write(tmp_path, text))
    assert set(table.column("finger").to_pylist()) == {"middle"}
    assert len(refused) == 1
    assert "lacks segment J3" in refused[0].reason and "index" in refused[0].reason
    assert refused[0].line == 2 and refused[0].field == "segment"


def test_bad_number_refuses_the_row_and_quarantines_its_finger(tmp_path):
    text = HEADER + "x1,index,J1,40,,,,\nx1,index,J2,abc,,,,\nx1,index,J3,18,,,,\n" \
        + _finger_rows("x1", "ring", (41.0, 26.0, 21.0))
    table, refused = read_xray(_write(tmp_path, text))
    assert set(table.column("finger").to_pylist()) == {"ring"}
    number = [e for e in refused if e.field == "length"]
    assert len(number) == 1 and number[0].line == 3 and "abc" in number[0].reason
    finger = [e for e in refused if e.field == "segment"]
    assert "refused on line(s) 3" in finger[0].reason


@pytest.mark.parametrize(("row", "field"), [
    ("x1,index,J1,-4,,,,", "length"),
    ("x1,index,J1,nan,,,,", "length"),
    ("x1,pointer,J1,40,,,,", "finger"),
    ("x1,thumb,J3,40,,,,", "segment"),
    ("x1,index,J1,40,,,old,", "age"),
    ("x1,index,J1,40,,,,up", "side"),
])
def test_bad_fields_are_named(tmp_path, row, field):
    _, refused = read_xray(_write(tmp_path, HEADER + row + "\n"))
    assert any(e.field == field and e.line == 2 for e in refused)
    assert all(str(tmp_path) in str(e) for e in refused)


def test_duplicate_segment_is_quarantined(tmp_path):
    text = HEADER + _finger_rows("x1", "index", (40.0, 22.0, 18.0)) + "x1,index,J2,23,,,,\n"
    table, refused = read_xray(_write(tmp_path, text))
    assert table.num_rows == 0
    assert len(refused) == 1 and "lines 3, 5" in refused[0].reason and refused[0].line == 5


def test_conflicting_metadata_quarantines_the_image(tmp_path):
    text = (HEADER + _finger_rows("x1", "index", (40.0, 22.0, 18.0), "s1,f,30,right")
            + _finger_rows("x1", "ring", (41.0, 26.0, 21.0), "s1,m,30,right")
            + _finger_rows("x2", "ring", (41.0, 26.0, 21.0), "s2,m,30,right"))
    table, refused = read_xray(_write(tmp_path, text))
    assert set(table.column("image_id").to_pylist()) == {"x2"}
    assert [e.field for e in refused] == ["sex"]


@pytest.mark.parametrize(("text", "field"), [
    ("", None),
    ("image_id,finger,segment\nx1,index,J1\n", "length"),
    ("image_id,finger,segment,length,colour\nx1,index,J1,3,red\n", "colour"),
    (HEADER, None),
])
def test_unreadable_files_are_refused_whole(tmp_path, text, field):
    table, refused = read_xray(_write(tmp_path, text))
    assert table.num_rows == 0
    assert len(refused) == 1 and isinstance(refused[0], InputError)
    assert refused[0].field == field
    assert refused[0].file.endswith("hands.xray.csv")


def test_short_row_is_refused(tmp_path):
    _, refused = read_xray(_write(tmp_path, "image_id,finger,segment,length\nx1,index,J1\n"))
    assert refused[0].line == 2 and refused[0].field == "length"
