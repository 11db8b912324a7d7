"""Every MeshMend plugin loads the way MeshLab loads it, every filter is well
declared, and every sample script can be run by Debian's meshlabserver
(which aborts on a missing, misnamed or mistyped parameter)."""
import xml.etree.ElementTree as ET

import pytest

from conftest import ROOT, filters, probe

CLASS_GENERIC = 0


def test_every_plugin_loads():
    loaded = probe()
    assert loaded, "no plugin built"
    for plugin in loaded:
        assert "error" not in plugin, plugin
    names = {p["file"] for p in loaded}
    assert "libfilter_mend_inspect.so" in names and "io_mend_obj.so" in names


def test_obj_importer_claims_obj():
    (obj,) = [p for p in probe() if p["file"] == "io_mend_obj.so"]
    assert obj["import_formats"] == ["OBJ"]


def test_filters_are_well_declared():
    declared = filters()
    assert "MeshMend: Inspect Mesh Defects" in declared
    for name, f in declared.items():
        assert name.startswith("MeshMend: "), name
        assert f["class"] != CLASS_GENERIC, f"{name}: a Generic class aborts MeshLab at start-up"
        assert len(f["info"]) > 80, f"{name}: filterInfo should explain the filter"
        params = [p["name"] for p in f["parameters"]]
        assert "report_file" in params, f"{name}: every filter has report_file"
        for p in f["parameters"]:
            assert len(p["tooltip"]) > 20, f"{name}/{p['name']}: tooltip missing"


def sample_steps():
    for script in sorted((ROOT / "samples").glob("*.mlx")):
        root = ET.parse(script).getroot()
        for step, element in enumerate(root.findall("filter")):
            yield pytest.param(script.name, element, id=f"{script.name}[{step}]")


@pytest.mark.parametrize("script,element", list(sample_steps()))
def test_samples_list_every_parameter_as_meshlab_writes_it(script, element):
    name = element.get("name")
    if not name.startswith("MeshMend: "):
        return  # MeshLab's own filters are MeshLab's business
    declared = {p["name"]: ET.fromstring(p["xml"]) for p in filters()[name]["parameters"]}
    written = {p.get("name"): p for p in element.findall("Param")}
    assert set(written) == set(declared), f"{script}: {name} parameters differ from the filter's"
    for pname, want in declared.items():
        got = written[pname]
        # Everything but the value and the texts must be as MeshLab writes it.
        for attribute, value in want.attrib.items():
            if attribute in ("value", "description", "tooltip"):
                continue
            assert got.get(attribute) == value, f"{script}: {name}/{pname} {attribute}"
