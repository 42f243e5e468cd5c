import numpy as np
import pyarrow as pa
import pytest

from handdb.errors import InputError
from handdb.ingest.delimited import TextLines, read_delimited, read_strings

NAMES = ["frame", "joint", "u", "v"]
TYPES = {"frame": pa.int64(), "u": pa.float64(), "v": pa.float64()}


@pytest.mark.parametrize(("text", "typed"), [
    (b"frame,joint,u,v\n0,wrist,1.5,2\n0,index_tip,,\n3,wrist, 4e2 ,-5.25\n", True),
    (b"frame,joint,u,v\r\n0, wrist ,1,2\r\n1,wrist,3,4", True),
    (b"\n\nframe,joint,u,v\n0,wrist,1,2\n", True),
    (b"frame,joint,u,v\n0,\"wrist\",1,2\n1,wrist,\"3\",4\n", False),
    (b"frame,joint,u,v\n0,wrist,1,2\n\n2,wrist,3,4\n\n", False),
    (b"frame,joint,u,v\n0,wrist,1,2\r\r\n1,wrist,3,4\n", False),
    (b"frame,joint,u,v\n0,wrist,  ,\n", False),
    (b"frame,joint,u,v\n\n0,wrist,1,2\n", False),
])
def test_typed_read_gives_what_the_string_read_parses(tmp_path, text, typed):
    path = tmp_path / "clip.tracks.csv"
    strings = read_strings(path, text, names=NAMES, header_lines=1)
    parsed = read_delimited(path, text, names=NAMES, header_lines=1, types=TYPES)
    assert pa.types.is_floating(parsed.columns["u"].type) is typed
    np.testing.assert_array_equal(parsed.line, strings.line)
    np.testing.assert_array_equal(parsed.frames("frame"), strings.frames("frame"))
    assert parsed.dictionary("joint")[0] == strings.dictionary("joint")[0]
    np.testing.assert_array_equal(parsed.dictionary("joint")[1], strings.dictionary("joint")[1])
    for axis in "uv":
        np.testing.assert_array_equal(parsed.numbers(axis, allow_empty=True),
                                      strings.numbers(axis, allow_empty=True))
    untyped = read_delimited(path, text, names=NAMES, header_lines=1)
    np.testing.assert_array_equal(untyped.line, strings.line)
    assert untyped.columns == strings.columns


@pytest.mark.parametrize(("text", "line", "field", "message"), [
    (b"frame,joint,u,v\n0,wrist,1,2\n1,wrist,inf,2\n", 3, "u", "'inf' is not a finite"),
    (b"frame,joint,u,v\n0,wrist,1,2\n,wrist,1,2\n", 3, "frame", "'' is not a whole frame"),
    (b"frame,joint,u,v\n0,wrist,1,2\n1,wrist,1\n", 3, None, "has 3 fields"),
])
def test_values_the_typed_read_refuses_are_named_by_the_string_read(tmp_path, text, line,
                                                                    field, message):
    path = tmp_path / "clip.tracks.csv"
    with pytest.raises(InputError, match=message) as info:
        table = read_delimited(path, text, names=NAMES, header_lines=1, types=TYPES)
        table.frames("frame")
        table.numbers("u", allow_empty=True)
    assert (info.value.line, info.value.field) == (line, field)


@pytest.mark.parametrize("text", [b"a\n\n\r\nb\r\nc", b"\n a\n\nb\n", b"a"])
def test_leading_lines_are_the_first_nonblank_lines(text):
    lines = TextLines.of(text)
    expected = [(int(n), int(lines.start[n - 1]), int(lines.end[n - 1]))
                for n in lines.nonblank[:2]]
    assert TextLines.leading(text, 2) == expected
