"""Python parity (issue 40): every parameter of every MeshMend filter, as the
plugins themselves declare it (tests/plugin_probe loads them the way MeshLab
does), is an option of the NumPy module's matching function under the same
name and with the same default. The only exceptions are the parameters that
name things of a MeshLab document (layers, the selection, layers the filter
creates), each listed below with what the module takes instead; a listed
parameter the filters no longer declare fails too, so that the list cannot
go stale.

Run from the build:  MESHMEND_BUILD_DIR=build /usr/bin/python3 -m pytest tests/python/test_parity.py
"""
import inspect
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("MESHMEND_BUILD_DIR", ROOT / "build"))
sys.path.insert(0, str(BUILD / "python"))
sys.path.append(str(ROOT / "tests"))

import meshmend as mm  # noqa: E402
from environment import need  # noqa: E402

# Each filter and the module functions that do what it does.
FUNCTIONS = {
    "MeshMend: Inspect Mesh Defects": ["inspect"],
    "MeshMend: Select Intersecting Faces": ["find_intersections"],
    "MeshMend: Intersect and Split Layers": ["intersect_and_split", "intersect_and_split_meshes"],
    "MeshMend: Remove Self-Intersections": ["remove_self_intersections"],
    "MeshMend: Fill Holes (Feature Preserving)": ["fill_holes"],
    "MeshMend: Trim Along Vertex Loop": ["trim_along_loop"],
    "MeshMend: Stitch Boundaries": ["stitch_boundaries", "stitch_sequence"],
    "MeshMend: Close Gaps Between Borders": ["close_gaps"],
    "MeshMend: Measure Clearance": ["measure_clearance"],
    "MeshMend: Enforce Minimum Clearance": ["enforce_clearance"],
    "MeshMend: Paint Surface Patches": ["paint_patches"],
    "MeshMend: Select Patches": ["select_patches"],
    "MeshMend: Remove Patches": ["remove_patches"],
}

# Filters with no counterpart on arrays, and why.
NO_FUNCTION = {
    "MeshMend: Prepare Shader View":
        "sets a layer's quality and colours for MeshLab's shaders: nothing to render on arrays",
}

LAYERS = "which layers of the document: the module takes the meshes as arguments"
DOCUMENT = {
    ("MeshMend: Inspect Mesh Defects", "select_defects"):
        "replaces the document's selection; the module returns the defects per element "
        "(mark_defects)",
    ("MeshMend: Select Intersecting Faces", "mode"):
        LAYERS + " (self and cross say which pairs)",
    ("MeshMend: Select Intersecting Faces", "first_layer"): LAYERS,
    ("MeshMend: Select Intersecting Faces", "second_layer"): LAYERS,
    ("MeshMend: Select Intersecting Faces", "segments_layer"):
        "a new layer; the module returns the segments with contacts=True",
    ("MeshMend: Intersect and Split Layers", "mode"):
        LAYERS + " (between_meshes and split_self_intersections say what is split)",
    ("MeshMend: Intersect and Split Layers", "first_layer"): LAYERS,
    ("MeshMend: Intersect and Split Layers", "second_layer"): LAYERS,
    ("MeshMend: Intersect and Split Layers", "output"):
        "where the result goes in the document; the module returns the merged mesh and, "
        "with separate_meshes (default), each mesh",
    ("MeshMend: Intersect and Split Layers", "curves_layer"):
        "a new layer; the module returns curve_edges",
    ("MeshMend: Fill Holes (Feature Preserving)", "selected_only"):
        "the document's selection; the module takes selected_vertices",
    ("MeshMend: Fill Holes (Feature Preserving)", "select_new_faces"):
        "sets the document's selection; the module returns new_faces",
    ("MeshMend: Trim Along Vertex Loop", "loop_vertices"):
        "an index list typed as text; the module takes the array `loop`",
    ("MeshMend: Trim Along Vertex Loop", "picked_vertices"):
        "vertices picked in the document's view, as text; the module takes the array "
        "picked_vertices",
    ("MeshMend: Trim Along Vertex Loop", "keep_side"):
        "the side of the document's selected face; the module keeps keep_face's side, or the "
        "left of the loop with keep_face=-1",
    ("MeshMend: Trim Along Vertex Loop", "removed_to_layer"):
        "a new layer; the module always returns the removed faces",
    ("MeshMend: Stitch Boundaries", "paths_from"):
        "where the paths come from in the document; the module takes index arrays a and b "
        "(stitch_boundaries) or paths and pairs (stitch_sequence)",
    ("MeshMend: Stitch Boundaries", "first_layer"): LAYERS,
    ("MeshMend: Stitch Boundaries", "second_layer"): LAYERS,
    ("MeshMend: Stitch Boundaries", "path_a"): "typed as text; the module takes the array a",
    ("MeshMend: Stitch Boundaries", "path_b"): "typed as text; the module takes the array b",
    ("MeshMend: Stitch Boundaries", "paths"):
        "typed as text; stitch_sequence takes the arrays `paths`",
    ("MeshMend: Stitch Boundaries", "stitch_pairs"):
        "typed as text; stitch_sequence takes `pairs`",
    ("MeshMend: Stitch Boundaries", "output"): "where the result goes in the document",
    ("MeshMend: Stitch Boundaries", "select_new_faces"):
        "sets the document's selection; the module returns new_faces",
    ("MeshMend: Close Gaps Between Borders", "all_visible_layers"): LAYERS,
    ("MeshMend: Close Gaps Between Borders", "select_new_faces"):
        "sets the document's selection; the module returns vertex_index and the faces",
    ("MeshMend: Measure Clearance", "first_layer"): LAYERS,
    ("MeshMend: Measure Clearance", "second_layer"): LAYERS,
    ("MeshMend: Enforce Minimum Clearance", "first_layer"): LAYERS,
    ("MeshMend: Enforce Minimum Clearance", "second_layer"): LAYERS,
    ("MeshMend: Enforce Minimum Clearance", "lock_selected"):
        "the document's selection; the module takes `locked`",
    ("MeshMend: Paint Surface Patches", "layers"): LAYERS + " (face_part / part)",
    ("MeshMend: Select Patches", "layers"): LAYERS + " (face_part)",
    ("MeshMend: Remove Patches", "layers"): LAYERS + " (part)",
}


# Options the module does not have yet, each an open item of the project
# (listed, so the test fails strictly once one is added: remove it here then).
NOT_YET = {}


def declared_filters():
    probe = BUILD / "tests" / "plugin_probe"
    plugins = sorted(str(p) for p in (BUILD / "plugins-out").glob("libfilter_mend_*.so"))
    need(probe.is_file() and plugins, f"the plugins and {probe} (built with the plugins)")
    out = subprocess.run([str(probe), *plugins], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return {f["name"]: f for p in json.loads(out.stdout)["plugins"] for f in p["filters"]}


@pytest.fixture(scope="module")
def filters():
    return declared_filters()


def filter_default(parameter):
    """The default as MeshLab writes it into a script: (kind, value)."""
    element = ET.fromstring(parameter["xml"])
    kind, text = parameter["type"], element.get("value")
    if kind == "RichBool":
        return kind, text == "true"
    if kind == "RichInt":
        return kind, int(text)
    if kind == "RichFloat":
        return kind, float(text)
    if kind == "RichEnum":
        return kind, (int(text), int(element.get("enum_cardinality")))
    if kind in ("RichAbsPerc", "RichDistance"):  # a distance: a fraction of the diagonal (max)
        return kind, float(text) / float(element.get("max"))
    return kind, text


def test_every_filter_has_a_function(filters):
    for name in filters:
        assert name in FUNCTIONS or name in NO_FUNCTION, f"{name}: no module function is named"
    for name in list(FUNCTIONS) + list(NO_FUNCTION):
        assert name in filters, f"{name} is no longer a filter"


def test_every_document_parameter_listed_is_declared(filters):
    for (name, parameter) in DOCUMENT:
        declared = {p["name"] for p in filters[name]["parameters"]}
        assert parameter in declared, f"{name} no longer has {parameter}"


def cases():
    return [(f, fn) for f, functions in FUNCTIONS.items() for fn in functions]


@pytest.mark.parametrize("filter_name,function", cases(), ids=[fn for _, fn in cases()])
def test_every_filter_parameter_is_an_option_with_the_same_default(filters, filter_name, function):
    options = inspect.signature(getattr(mm, function)).parameters
    problems = []
    for parameter in filters[filter_name]["parameters"]:
        name = parameter["name"]
        if (filter_name, name) in DOCUMENT:
            continue
        if name not in options:
            problems.append(f"{name}: missing")
            continue
        if (function, name) in NOT_YET:
            problems.append(f"{name}: present, remove it from NOT_YET")
        ours = options[name].default
        kind, theirs = filter_default(parameter)
        if kind == "RichEnum":
            index, cardinality = theirs
            choices = mm.FILTER_CHOICES.get(function, {}).get(name)
            if choices is None:  # an integer option
                same = isinstance(ours, int) and ours == index
            else:
                if len(choices) != cardinality:
                    problems.append(f"{name}: {len(choices)} choices, the filter has {cardinality}")
                    continue
                same = ours == choices[index] or (isinstance(ours, int) and ours == index)
            theirs = index
        elif kind in ("RichAbsPerc", "RichDistance"):
            same = isinstance(ours, str) and ours.endswith("%") and np.isclose(
                float(ours[:-1]) / 100, theirs, rtol=1e-5, atol=0)
            theirs = f"{theirs * 100:g}% of the diagonal"
        elif kind == "RichFloat":
            same = isinstance(ours, (int, float)) and not isinstance(ours, bool) and np.isclose(
                float(np.float32(ours)), theirs, rtol=1e-6, atol=0)
        elif kind == "RichBool":
            same = isinstance(ours, bool) and ours == theirs
        else:
            same = type(ours) is type(theirs) and ours == theirs
        if not same:
            problems.append(f"{name}: default {ours!r}, the filter's {theirs!r}")
    known = [p.split(":")[0] for p in problems
             if p.endswith(": missing") and (function, p.split(":")[0]) in NOT_YET]
    if problems and len(known) == len(problems):
        pytest.xfail("; ".join(f"{name}: {NOT_YET[(function, name)]}" for name in known))
    assert not problems, f"{function} against '{filter_name}':\n  " + "\n  ".join(problems)


def test_enum_options_take_the_filter_s_index_too():
    """A script's value (the filter's index) works as the option's value."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    V2 = V + [0.25, 0.25, 0.25]
    by_name = mm.measure_clearance(V, F, V2, F, scope="between_layers", tau=0.01)
    by_index = mm.measure_clearance(V, F, V2, F, scope=1, tau=0.01)
    assert by_name.report == {**by_index.report, "time_ms": by_name.report["time_ms"]}
    with pytest.raises(mm.InvalidInputError, match="scope"):
        mm.measure_clearance(V, F, scope=3)


def test_distances_take_a_percentage_of_the_diagonal():
    V = np.array([[0, 0, 0], [3, 0, 0], [0, 4, 0], [0, 0, 12]], float)  # diagonal 13
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    assert mm.measure_clearance(V, F, tau="10%").report["tau"] == pytest.approx(1.3)
    assert mm.measure_clearance(V, F, tau=1.3).report["tau"] == pytest.approx(1.3)
    with pytest.raises(mm.InvalidInputError, match="percentage"):
        mm.measure_clearance(V, F, tau="ten%")


def test_report_file_writes_the_report(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    path = tmp_path / "report.json"
    report = mm.inspect(V, F, report_file=str(path))
    written = json.loads(path.read_text())
    assert written["faces"] == report["faces"] == 4 and written["is_closed"]
