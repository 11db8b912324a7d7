"""The MeshLab 2022.02 flavour of the plugins (what pymeshlab 2022.2 loads
with pymeshlab.load_plugin), run through MeshLab 2022.02's own plugin system
by meshlab2022_host (scripts/setup-pymeshlab-flavour builds both): every
plugin passes the PluginManager's checks, every filter has its stable python
name and the 2020.09 flavour's parameters, returns its report as the result
map, raises MLException on bad input, and gives the same counts as the
2020.09 flavour run by meshlabserver on the same real meshes."""
import json
import os
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from conftest import (BUILD, DATA, PLUGIN_DIR, filters, meshcheck, mlx, read_ply,
                      require_shared_data, run_server, write_off, write_ply)
from test_clearance import nested_spheres
from test_stitch import indices, joined, sphere, two_sheets

FLAVOUR = Path(os.environ.get("MESHMEND_PYMESHLAB_FLAVOUR_DIR", BUILD / "pymeshlab-flavour"))
HOST = FLAVOUR / "pymeshlab-host" / "meshlab2022_host"
PLUGINS = sorted(str(p) for p in (FLAVOUR / "plugins-out").glob("libfilter_mend_*.so"))

PYTHON_NAMES = {
    "MeshMend: Inspect Mesh Defects": "meshmend_inspect_defects",
    "MeshMend: Select Intersecting Faces": "meshmend_select_intersecting_faces",
    "MeshMend: Intersect and Split Layers": "meshmend_intersect_and_split",
    "MeshMend: Paint Surface Patches": "meshmend_paint_patches",
    "MeshMend: Select Patches": "meshmend_select_patches",
    "MeshMend: Remove Patches": "meshmend_remove_patches",
    "MeshMend: Remove Self-Intersections": "meshmend_remove_self_intersections",
    "MeshMend: Fill Holes (Feature Preserving)": "meshmend_fill_holes",
    "MeshMend: Measure Clearance": "meshmend_measure_clearance",
    "MeshMend: Enforce Minimum Clearance": "meshmend_enforce_minimum_clearance",
    "MeshMend: Trim Along Vertex Loop": "meshmend_trim_along_vertex_loop",
    "MeshMend: Stitch Boundaries": "meshmend_stitch_boundaries",
    "MeshMend: Close Gaps Between Borders": "meshmend_close_gaps",
    "MeshMend: Prepare Shader View": "meshmend_prepare_shader_view",
}
NAMES = {python: name for name, python in PYTHON_NAMES.items()}


@pytest.fixture(scope="module", autouse=True)
def flavour_built():
    if not HOST.is_file() or not PLUGINS:
        message = (f"the MeshLab 2022.02 flavour is not built ({HOST} missing): "
                   "run scripts/setup-pymeshlab-flavour")
        if os.environ.get("MESHMEND_REQUIRE_PYMESHLAB_FLAVOUR") == "1":
            pytest.fail(message)
        pytest.skip(message)


def host(*args, plugins=None, timeout=600):
    proc = subprocess.run([str(HOST), *args[:1], *(PLUGINS if plugins is None else plugins),
                           *args[1:]], capture_output=True, text=True, timeout=timeout)
    try:
        out = json.loads(proc.stdout)
    except json.JSONDecodeError:
        raise AssertionError(f"host printed no JSON (exit {proc.returncode}):\n"
                             f"{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}")
    return proc.returncode, out


def run_host(tmp_path, inputs, steps, save=None):
    """Applies the steps ((python name, {param: value}), ...) to the meshes in
    one document; each step writes its report to report<i>.json."""
    args = ["apply"]
    for i in inputs:
        args += ["--mesh", str(i)]
    reports = []
    for k, (name, values) in enumerate(steps):
        path = tmp_path / f"host{k}.json"
        reports.append(path)
        args += ["--filter", name, "--param", f"report_file={path}"]
        for key, value in values.items():
            value = ("true" if value else "false") if isinstance(value, bool) else value
            args += ["--param", f"{key}={value}"]
    if save:
        args += ["--save", str(save)]
    code, out = host(*args)
    return code, out, [json.loads(p.read_text()) if p.exists() else None for p in reports]


def run_both(tmp_path, inputs, steps, save=None):
    """The same steps through meshlabserver (2020.09 flavour) and the host
    (2022.02 flavour); both must succeed. Returns the reports of each and the
    host's output. With `save`, the server's current layer is written to
    save/server.ply and every layer of the host's document to save/<id>.ply."""
    script = mlx(*[(NAMES[name], {**values, "report_file": "{report%d}" % k})
                   for k, (name, values) in enumerate(steps)])
    if save:
        save.mkdir(parents=True, exist_ok=True)
    server = run_server(tmp_path, inputs, script, outputs=[save / "server.ply"] if save else ())
    assert server.returncode == 0, server.log[-3000:]
    # Per step (run_server keeps only the reports written).
    ours = [json.loads(p.read_text()) if p.exists() else None
            for p in (tmp_path / f"report{k}.json" for k in range(len(steps)))]
    code, out, theirs = run_host(tmp_path, inputs, steps, save)
    assert code == 0, json.dumps(out, indent=1)[-3000:]
    return ours, theirs, out


def assert_same_geometry(server_ply, host_ply, kept=0):
    """The same faces, and vertices equal up to float rounding: the 2020.09
    flavour reads and writes float, MeshLab 2022.02 double, and the input's
    rounding carries through a solve to the new vertices (1e-6 of the
    diagonal bounds it); the first `kept` vertices, input vertices left in
    place, are equal once rounded to float."""
    V32, F32, _ = read_ply(server_ply)
    V64, F64, _ = read_ply(host_ply)
    assert np.array_equal(F32, F64)
    diagonal = np.linalg.norm(V64.max(axis=0) - V64.min(axis=0))
    assert np.abs(V32 - V64).max() <= 1e-6 * diagonal
    assert np.array_equal(V32[:kept], V64[:kept].astype(np.float32).astype(float))


def counts(report):
    """The report's counts and verdicts: integer, boolean and string values
    (recursively), without timings."""
    if isinstance(report, dict):
        return {k: counts(v) for k, v in report.items()
                if not ("time" in k or k.endswith("_ms")) and counts(v) is not None}
    if isinstance(report, list):
        items = [counts(v) for v in report]
        return items if all(i is not None for i in items) else None
    if isinstance(report, (bool, int, str)):
        return report
    return None  # floats: geometry, compared separately


def assert_result_map_is_the_report(step, report):
    """The map the filter returned holds the report_file's keys and values:
    numbers as int or double, booleans as bool, numeric arrays as vectors
    (what pymeshlab converts), strings and other values as QString."""
    result, types = step["result"], step["result_types"]
    assert set(result) == set(report), (set(result) ^ set(report))
    for key, value in report.items():
        if isinstance(value, bool):
            assert types[key] == "bool" and result[key] is value, key
        elif isinstance(value, int):
            assert types[key] in ("int", "double") and result[key] == value, key
        elif isinstance(value, float):
            assert types[key] == "double" and result[key] == value, key
        elif value is None:
            assert types[key] == "double" and result[key] is None, key  # NaN
        elif isinstance(value, str):
            assert types[key] == "QString" and result[key] == value, key
        elif isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                             for v in value):
            assert types[key] == "Eigen::VectorXd", (key, types[key])
            assert result[key] == [float(v) for v in value], key
        else:
            assert types[key] == "QString" and json.loads(result[key]) == value, key


def compare(server_reports, host_reports, out, differing={}):
    """Same counts in every step's report (keys in differing[step] aside),
    and each step's result map equal to its report."""
    for k, (ours, theirs, step) in enumerate(zip(server_reports, host_reports, out["steps"])):
        assert "error" not in step, step
        assert theirs is not None, f"step {k} wrote no report"
        assert_result_map_is_the_report(step, theirs)
        a, b = counts(ours), counts(theirs)
        for key in differing.get(k, ()):
            a.pop(key, None), b.pop(key, None)
        assert a == b, {key: (a.get(key), b.get(key)) for key in set(a) | set(b)
                        if a.get(key) != b.get(key)}


# ---- the plugins in MeshLab 2022.02's plugin system --------------------------------

def test_every_plugin_loads_and_passes_the_checks():
    code, out = host("list")
    assert code == 0, out
    assert len(out["plugins"]) == len(PLUGINS) == len(list(PLUGIN_DIR.glob("libfilter_mend_*.so")))
    for p in out["plugins"]:
        assert p["filter_plugin"] and p["double_precision"], p
        assert p["meshlab_version"].startswith("2022.02"), p
    listed = {f["python_name"]: f for f in out["filters"]}
    assert set(listed) == set(NAMES), set(listed) ^ set(NAMES)
    # The same filters and parameter names as the 2020.09 flavour.
    old = filters()
    for python, f in listed.items():
        assert f["name"] == NAMES[python]
        assert [p["name"] for p in f["parameters"]] == \
            [p["name"] for p in old[f["name"]]["parameters"]], python
        assert f["class"] == old[f["name"]]["class"] and f["arity"] == old[f["name"]]["arity"]
    # Defaults as pymeshlab computes them (on its 1x1x1 cube), those of the
    # 2020.09 flavour's dialog.
    holes = {p["name"]: p for p in listed["meshmend_fill_holes"]["parameters"]}
    dialog = {p["name"]: ET.fromstring(p["xml"]).get("value")
              for p in old[NAMES["meshmend_fill_holes"]]["parameters"]}
    assert holes["max_diameter"]["type"] == "RichFloat"
    assert holes["max_diameter"]["default"] == float(dialog["max_diameter"]) == 0.5
    assert holes["fairing"]["type"] == "RichEnum"
    assert str(holes["fairing"]["default"]) == dialog["fairing"]
    assert holes["selected_only"]["default"] is False and dialog["selected_only"] == "false"
    assert holes["report_file"]["default"] == ""


def test_the_float_flavour_is_refused_by_the_checks():
    """A 2020.09 plugin (float, MeshFilterInterface) is not loaded."""
    old = PLUGIN_DIR / "libfilter_mend_holes.so"
    assert old.is_file()
    code, out = host("list", plugins=[str(old)])
    assert code == 2 and "libfilter_mend_holes.so" in out["refused"], out


def test_errors_are_mlexceptions_and_leave_the_document(tmp_path):
    V = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    path = write_off(tmp_path / "tri.off", V, [(0, 1, 2)])
    code, out, reports = run_host(tmp_path, [path], [("meshmend_intersect_and_split", {})])
    assert code == 1 and reports == [None]
    assert "does not intersect itself: nothing to split" in out["steps"][0]["error"]
    assert [(l["vertices"], l["faces"]) for l in out["layers"]] == [(3, 1)]
    code, out, _ = run_host(tmp_path, [path], [("meshmend_fill_holes", {"max_boundary_edges": -1})])
    assert code == 1 and "max hole size" in out["steps"][0]["error"]
    code, out, _ = run_host(tmp_path, [path], [("meshmend_measure_clearance", {"tau": -1})])
    assert code == 1 and "tau must be a distance of 0 or more" in out["steps"][0]["error"]


# ---- every filter, both flavours, the same counts ---------------------------------

def test_inspect(tmp_path):
    require_shared_data()
    ours, theirs, out = run_both(tmp_path, [DATA / "stanford/bun_zipper_res2.ply"],
                                 [("meshmend_inspect_defects", {"select_defects": 3})])
    compare(ours, theirs, out)
    assert theirs[0]["border_loops"] > 0 and not theirs[0]["is_closed"]
    assert out["layers"][0]["selected_faces"] > 0  # the border faces (select_defects 3)


def test_intersect_split_paint_select_remove(tmp_path):
    require_shared_data()
    inputs = [DATA / "pairs/ballA.off", DATA / "pairs/ballB.off"]
    ours, theirs, out = run_both(tmp_path, inputs, [
        ("meshmend_select_intersecting_faces", {"mode": 1, "first_layer": 0, "second_layer": 1}),
        ("meshmend_intersect_and_split", {"mode": 1, "first_layer": 0, "second_layer": 1,
                                          "output": 1}),
        ("meshmend_paint_patches", {}),
        ("meshmend_select_patches", {"by": 5}),
        ("meshmend_remove_patches", {"keep": 0, "removed_to_layer": True})],
        save=tmp_path / "saved")
    compare(ours, theirs, out)
    assert theirs[0]["cross_intersecting_pairs"] == theirs[1]["intersecting_pairs"] > 0
    assert theirs[1]["remaining_intersecting_pairs"] == 0 and theirs[2]["patches"] == 4
    assert theirs[3]["patches_selected"] == theirs[4]["patches_removed"] == 2  # the inner halves
    assert theirs[4]["is_closed"] and theirs[4]["remaining_intersecting_pairs"] == 0
    labels = [l["label"] for l in out["layers"]]
    assert labels == ["ballA.off", "ballB.off", "intersected", "removed patches"], labels
    kept = out["layers"][2]  # the patches kept in place, the others moved to a layer
    assert kept["faces"] == theirs[4]["faces_out"] and out["layers"][3]["faces"] > 0
    check = meshcheck(tmp_path / "saved" / f"{kept['id']}.ply")
    assert check["is_closed"] and check["self_intersecting_pairs"] == 0, check
    assert check["faces"] == kept["faces"]


def test_remove_self_intersections(tmp_path):
    require_shared_data()
    ours, theirs, out = run_both(tmp_path, [DATA / "self_intersecting/cow.off"],
                                 [("meshmend_remove_self_intersections", {})],
                                 save=tmp_path / "saved")
    compare(ours, theirs, out)
    assert theirs[0]["remaining_intersecting_pairs"] == 0
    assert meshcheck(tmp_path / "saved" / "0.ply")["self_intersecting_pairs"] == 0
    assert_same_geometry(tmp_path / "saved" / "server.ply", tmp_path / "saved" / "0.ply")


def test_fill_holes(tmp_path):
    require_shared_data()
    ours, theirs, out = run_both(tmp_path, [DATA / "holes/mech-holes-shark.off"],
                                 [("meshmend_fill_holes", {})], save=tmp_path / "saved")
    compare(ours, theirs, out)
    assert theirs[0]["holes_filled"] > 0
    after = meshcheck(tmp_path / "saved" / "0.ply")
    before = meshcheck(DATA / "holes/mech-holes-shark.off")
    assert after["border_loops"] == before["border_loops"] - theirs[0]["holes_filled"]
    assert_same_geometry(tmp_path / "saved" / "server.ply", tmp_path / "saved" / "0.ply",
                         kept=before["vertices"])


def test_measure_and_enforce_clearance(tmp_path):
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    ours, theirs, out = run_both(tmp_path, [src], [
        ("meshmend_measure_clearance", {"tau": 0.06}),
        ("meshmend_enforce_minimum_clearance", {"tau": 0.06}),
        ("meshmend_measure_clearance", {"tau": 0.06}),
        ("meshmend_prepare_shader_view", {"values": 0})], save=tmp_path / "saved")
    # The expected differences: 2022.02 stores double, so nothing is rounded to
    # float; after enforcing, many pairs lie at tau to rounding, and which of
    # them measures closest depends on float or double.
    assert ours[1]["rounded_to_float"] and not theirs[1]["rounded_to_float"]
    compare(ours, theirs, out, differing={1: ("rounded_to_float",), 2: ("closest", "shortest")})
    assert theirs[0]["violating_pairs"] > 0
    assert theirs[1]["reached"] and theirs[1]["violating_pairs_after"] == 0
    after = meshcheck(tmp_path / "saved" / "0.ply", "--min-distance")
    assert after["min_distance"]["distance"] >= 0.06 * (1 - 1e-9)
    assert theirs[2]["violating_pairs"] == 0
    assert theirs[3]["values"] == "clearance" and theirs[3]["faces"] == len(F)


def test_trim_stitch_and_close_gaps(tmp_path):
    nlat, nlon = 8, 12
    V, F, ring = sphere(nlat, nlon)
    ball = write_off(tmp_path / "sphere.off", V, F)
    equator = [ring(nlat // 2, j) for j in range(nlon)]
    ours, theirs, out = run_both(tmp_path, [ball], [
        ("meshmend_trim_along_vertex_loop", {"loop_vertices": indices(equator), "keep_side": 1,
                                             "keep_face": len(F) - 1})])
    compare(ours, theirs, out)

    A, B, pa, pb = two_sheets(7, 11)
    sheets = write_off(tmp_path / "sheets.off", *joined(A, B))
    ours, theirs, out = run_both(tmp_path, [sheets], [
        ("meshmend_stitch_boundaries", {"path_a": indices(pa),
                                        "path_b": indices(p + len(A[0]) for p in pb)})])
    compare(ours, theirs, out)
    assert theirs[0]["faces_added"] == 6 + 10

    require_shared_data()
    ours, theirs, out = run_both(tmp_path, [DATA / "stitching/quads_to_stitch.off"],
                                 [("meshmend_close_gaps", {})])
    compare(ours, theirs, out)
    assert theirs[0]["border_edges_after"] < theirs[0]["border_edges_before"]
