import pytest

from handdb.errors import RegistryError, UnknownNameError
from handdb.export import FORMATS as EXPORTS
from handdb.gapfill import METHODS as GAP_FILLING
from handdb.ingest.registry import FORMATS
from handdb.lifting import METHODS as LIFTING
from handdb.registry import Registry


def test_a_name_is_registered_once():
    registry = Registry[int]("number")
    registry.add("one", 1)
    with pytest.raises(RegistryError, match="number 'one' is registered twice"):
        registry.add("one", 1)
    assert registry.names() == ("one",) and registry["one"] == 1


def test_an_unknown_name_lists_the_known_ones():
    registry = Registry[int]("number")
    registry.add("one", 1)
    registry.add("two", 2)
    with pytest.raises(UnknownNameError, match="unknown number 'three'; known: one, two"):
        registry["three"]
    assert isinstance(UnknownNameError("x", "y", ()), ValueError)


@pytest.mark.parametrize("registry, names", [
    (FORMATS, {"tracks_csv", "openpose", "dlc", "mediapipe", "maya", "truth_csv",
               "markers_csv", "c3d", "xray"}),
    (LIFTING, {"thesis", "thesis-nocheck", "kinematic", "kinematic-refined", "model-fit"}),
    (GAP_FILLING, {"previous", "previous-diff", "interfinger", "intrafinger",
                   "intrafinger-rate", "linear", "cubic", "pchip", "lowrank", "rigid",
                   "auto"}),
    (EXPORTS, {"usd", "usdz", "bvh", "glb", "fbx", "trc", "c3d"}),
])
def test_every_registry_is_filled_by_importing_its_package(registry, names):
    assert names <= set(registry)


def test_the_inbox_knows_xray_files_without_importing_their_reader(tmp_path):
    import subprocess
    import sys

    (tmp_path / "table1.xray.csv").write_text("image_id,finger,segment,length\n")
    code = ("import sys; from handdb.ingest.inbox import discover; "
            "print(sorted(discover(sys.argv[1]).others))")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                         text=True, check=True).stdout
    assert out.strip() == "['xray']"


def test_a_lazy_entry_is_the_function_it_names():
    from handdb.gapfill.rigid import fill_rigid
    from handdb.lifting.kinematic import lift_kinematic

    assert LIFTING["kinematic"].function is lift_kinematic
    assert GAP_FILLING["rigid"].fill.function is fill_rigid
    assert GAP_FILLING["pchip"].fill.function.__name__ == "fill_pchip"
