"""The export formats: one registry, suffixes that name one format, writers loaded lazily."""

import subprocess
import sys

import pytest

from handdb.errors import ParameterError
from handdb.export import FORMATS
from handdb.export.formats import format_for_suffix


def test_every_suffix_names_one_format():
    suffixes = [suffix for entry in FORMATS.values() for suffix in entry.suffixes]
    assert len(suffixes) == len(set(suffixes))
    for entry in FORMATS.values():
        assert all(format_for_suffix(f"clip{suffix}") is entry for suffix in entry.suffixes)
    assert format_for_suffix("CLIP.TRC").name == "trc"


def test_an_unknown_suffix_lists_the_known_ones():
    with pytest.raises(ParameterError, match=r"clip\.obj: handdb writes no '\.obj' files; "
                       r"the suffix must be one of \.usd, \.usdc, \.usda, \.usdz, \.bvh"):
        format_for_suffix("clip.obj")


def test_every_writer_loads_and_marker_formats_take_missing_joints():
    assert all(callable(entry.load()) for entry in FORMATS.values())
    assert {entry.name for entry in FORMATS.values() if not entry.posed} == {"trc", "c3d"}


def test_listing_the_formats_and_writing_trc_import_no_usd_gltf_or_blender():
    code = ("import sys; from handdb.cli.export import export_clips; "
            "from handdb.export.stored import write_trc; from handdb.export import trc; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "{'pxr', 'pygltflib', 'bpy', 'trimesh'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
