"""MeshMend's double plugins in real pymeshlab: 2025.7 (MeshLab 2025.07d) and
2022.2.post2 (MeshLab 2022.02d), both built from ../shared/vendor by
scripts/hosts and loaded with pymeshlab.load_plugin. Every filter runs
through ms.apply_filter on real meshes and gives the counts of the 2020.09
flavour run by meshlabserver on the same inputs (its float rounding named
where it differs), its result dict holds its report, errors arrive as
pymeshlab exceptions with the meshes unchanged, and a plugin built for
another MeshLab or scalar is refused with a message that says so."""
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import cad_cases
from conftest import (BUILD, DATA, ROOT, PLUGIN_DIR, Host, filters, float_exact, meshcheck, mlx, need, read_ply,
                      require_shared_data, run_server, write_off, write_ply)
from test_clearance import nested_spheres
from test_stitch import indices, joined, sphere, two_sheets

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


@pytest.fixture(scope="module", params=["2025.07d", "2022.02d"])
def host(request):
    h = Host(request.param)
    h.require_pymeshlab()
    h.require_plugins()
    return h


def job(host, tmp_path, meshes=(), steps=(), save=None, plugins=None, describe=()):
    """Runs the steps ((python name, {param: value}) or a script path) in the
    host's pymeshlab on the meshes, with the host's plugins loaded."""
    return host.pymeshlab_job({
        "plugins": [str(p) for p in (host.plugins if plugins is None else plugins)],
        "meshes": [str(m) for m in meshes],
        "steps": [{"script": str(s)} if not isinstance(s, tuple) else {"filter": s[0], "params": s[1]}
                  for s in steps],
        "save": str(save) if save else None, "describe": list(describe)}, tmp_path)


def run_both(host, tmp_path, inputs, steps, save=None):
    """The same steps through meshlabserver (2020.09, float) and pymeshlab;
    both must succeed. Returns the server's reports, pymeshlab's reports (from
    report_file) and the job's output; with `save`, the server's current layer
    is written to save/server.ply and every pymeshlab layer to save/<id>.ply."""
    def in_script(v):  # an absolute distance is the plain value in a script
        return v["abs"] if isinstance(v, dict) else v
    script = mlx(*[(NAMES[name], {**{k: in_script(v) for k, v in values.items()},
                                  "report_file": "{report%d}" % k})
                   for k, (name, values) in enumerate(steps)])
    if save:
        save.mkdir(parents=True, exist_ok=True)
    server = run_server(tmp_path, inputs, script, outputs=[save / "server.ply"] if save else ())
    assert server.returncode == 0, server.log[-3000:]
    ours = [json.loads(p.read_text()) if p.exists() else None
            for p in (tmp_path / f"report{k}.json" for k in range(len(steps)))]
    paths = [tmp_path / f"py{k}.json" for k in range(len(steps))]
    out = job(host, tmp_path, inputs,
              [(name, {**values, "report_file": str(p)}) for (name, values), p in zip(steps, paths)],
              save=save)
    for k, step in enumerate(out["steps"]):
        assert "error" not in step, (k, step)
    assert len(out["steps"]) == len(steps)
    theirs = [json.loads(p.read_text()) if p.exists() else None for p in paths]
    return ours, theirs, out


def assert_same_geometry(server_ply, host_ply, kept=0):
    """The same faces, and vertices equal up to float rounding: 2020.09 reads
    and writes float, the double hosts double, and the input's rounding
    carries through a solve to the new vertices (1e-6 of the diagonal bounds
    it); the first `kept` vertices, input vertices left in place, are equal
    once rounded to float."""
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


def numbers(value):
    return isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                           for v in value)


def assert_result_is_the_report(result, report):
    """The dict apply_filter returned holds the report_file's numbers,
    verdicts and numeric arrays (pymeshlab converts those types and skips
    strings and nested values with a warning: they are read from report_file)."""
    expected = {k: v for k, v in report.items()
                if v is None or isinstance(v, (bool, int, float)) or numbers(v)}
    assert set(result) == set(expected), set(result) ^ set(expected)
    for key, value in expected.items():
        if isinstance(value, bool):
            assert result[key] is value, key
        elif numbers(value):
            assert result[key] == [float(v) for v in value], key
        else:
            assert result[key] == value, (key, result[key], value)


# Report keys that name the host's precision (float in 2020.09, double in
# the others): they differ by construction.
PRECISION_KEYS = ("host_scalar",)


def compare(server_reports, host_reports, out, differing={}):
    """Same counts in every step's report (keys in differing[step] aside),
    and each step's result dict holding its report."""
    for k, (ours, theirs, step) in enumerate(zip(server_reports, host_reports, out["steps"])):
        assert theirs is not None, f"step {k} wrote no report"
        assert_result_is_the_report(step["result"], theirs)
        a, b = counts(ours), counts(theirs)
        for key in PRECISION_KEYS + tuple(differing.get(k, ())):
            a.pop(key, None), b.pop(key, None)
        assert a == b, {key: (a.get(key), b.get(key)) for key in set(a) | set(b)
                        if a.get(key) != b.get(key)}


# ---- loading ---------------------------------------------------------------------

def test_every_plugin_loads_with_the_2020_09_filters_and_parameters(host, tmp_path):
    mesh = write_off(tmp_path / "tri.off", [(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
    out = job(host, tmp_path, [mesh], describe=list(NAMES))
    assert len(out["plugins"]) == len(host.plugins) == len(list(PLUGIN_DIR.glob("libfilter_mend_*.so")))
    assert all("error" not in p for p in out["plugins"]), out["plugins"]
    old = filters()
    assert set(PYTHON_NAMES) == set(old)
    for python, described in out["describe"].items():
        declared = [p["name"] for p in old[NAMES[python]]["parameters"]]
        assert list(described["defaults"]) == declared, python
        assert list(described["types"]) == declared, python
    # Defaults as pymeshlab computes them on the mesh: the 2020.09 dialog's.
    holes = out["describe"]["meshmend_fill_holes"]
    dialog = {p["name"]: p for p in old[NAMES["meshmend_fill_holes"]]["parameters"]}
    assert holes["defaults"]["max_diameter"] == pytest.approx(0.5)
    assert holes["defaults"]["selected_only"] is False and holes["defaults"]["report_file"] == ""
    assert 'value="0.5"' in dialog["max_diameter"]["xml"]


def test_a_plugin_built_for_another_host_is_refused(host, tmp_path):
    """pymeshlab's PluginManager refuses a plugin of another MeshLab version
    or scalar, naming the file; the host's own plugins still load."""
    others = {"2020.09": PLUGIN_DIR, "2025.07": BUILD / "hosts" / "2025.07" / "plugins-out",
              "2025.07d": BUILD / "hosts" / "2025.07d" / "plugins-out",
              "2022.02d": BUILD / "hosts" / "2022.02d" / "plugins-out"}
    for name, folder in others.items():
        plugin = folder / "libfilter_mend_holes.so"
        if name == host.name:
            continue
        need(plugin.is_file(), f"{plugin}: scripts/hosts build {name}")
        out = job(host, tmp_path, plugins=[plugin, *host.plugins])
        refused = out["plugins"][0]
        assert refused["exception"] == "PyMeshLabException", refused
        assert "libfilter_mend_holes.so" in refused["error"], refused
        if name == "2020.09":  # the old plugin interface
            assert "plugin" in refused["error"].lower()
        elif name == "2025.07":
            assert "floating point precision" in refused["error"], refused
        else:
            assert "different version" in refused["error"], refused
        assert all("error" not in p for p in out["plugins"][1:])


def test_errors_are_exceptions_and_leave_the_meshes(host, tmp_path):
    V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    path = write_off(tmp_path / "tet.off", V, [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)])
    cases = [
        (("meshmend_fill_holes", {"max_boundary_edges": -1}), "max hole size"),
        (("meshmend_measure_clearance", {"tau": {"abs": -1}}), "tau must be a distance of 0 or more"),
        (("meshmend_fill_holes", {"no_such_parameter": 1}), "no_such_parameter"),
        # pymeshlab casts the value before the filter sees it: its own message.
        (("meshmend_fill_holes", {"max_boundary_edges": "many"}), "Unable to cast"),
        (("meshmend_fill_holes", {"fairing": "No such shape"}), "No such shape"),
        (("meshmend_no_such_filter", {}), "meshmend_no_such_filter"),
    ]
    for step, message in cases:
        out = job(host, tmp_path, [path], [step], save=tmp_path / "saved")
        assert "error" in out["steps"][0], (step, out["steps"])
        assert message in out["steps"][0]["error"], (step, out["steps"][0])
        assert out["steps"][0]["exception"] in ("PyMeshLabException", "InvalidEnumException",
                                                 "RuntimeError", "AttributeError"), out["steps"][0]
        assert [(l["vertices"], l["faces"]) for l in out["layers"]] == [(4, 4)]
        V2, F2, _ = read_ply(tmp_path / "saved" / "0.ply")
        assert np.array_equal(V2, np.array(V, float)) and len(F2) == 4


def test_the_sample_scripts_load_in_pymeshlab(host, tmp_path):
    """Every sample names its filters and parameters as pymeshlab reads them."""
    ball = write_off(tmp_path / "tet.off", [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
                     [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)])
    from conftest import ROOT
    for sample in sorted((ROOT / "samples").glob("*.mlx")):
        out = job(host, tmp_path, [ball, ball], [sample])
        step = out["steps"][0]
        # Applying may fail on this input (nothing to trim, no selection);
        # reading the script may not.
        assert "error" not in step or "could not" not in step["error"].lower() \
            and "not found" not in step["error"].lower(), (sample.name, step)


# ---- every filter, both routes, the same counts ---------------------------------------

def test_inspect(host, tmp_path):
    require_shared_data()
    ours, theirs, out = run_both(host, tmp_path, [DATA / "stanford/bun_zipper_res2.ply"],
                                 [("meshmend_inspect_defects", {"select_defects": 3})])
    compare(ours, theirs, out)
    assert theirs[0]["border_loops"] > 0 and not theirs[0]["is_closed"]
    assert out["layers"][0]["selected_faces"] > 0  # the border faces (select_defects 3)


def test_intersect_split_paint_select_remove(host, tmp_path):
    require_shared_data()
    inputs = [DATA / "pairs/ballA.off", DATA / "pairs/ballB.off"]
    ours, theirs, out = run_both(host, tmp_path, inputs, [
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


def test_remove_self_intersections(host, tmp_path):
    require_shared_data()
    ours, theirs, out = run_both(host, tmp_path, [DATA / "self_intersecting/cow.off"],
                                 [("meshmend_remove_self_intersections", {})],
                                 save=tmp_path / "saved")
    compare(ours, theirs, out)
    assert theirs[0]["remaining_intersecting_pairs"] == 0
    assert meshcheck(tmp_path / "saved" / "0.ply")["self_intersecting_pairs"] == 0
    assert_same_geometry(tmp_path / "saved" / "server.ply", tmp_path / "saved" / "0.ply")


def test_fill_holes(host, tmp_path):
    require_shared_data()
    shark = float_exact(DATA / "holes/mech-holes-shark.off", tmp_path / "shark.off")
    ours, theirs, out = run_both(host, tmp_path, [shark],
                                 [("meshmend_fill_holes", {})], save=tmp_path / "saved")
    # The patches are decided on the coordinates as the host stores them
    # (float in 2020.09, double here): a hole's refinement may then take a
    # few different steps. Named and bounded: each hole's added faces and
    # vertices within 2 %, everything else equal.
    sizes = ("faces_added", "vertices_added")
    compare(ours, theirs, out, differing={0: sizes + ("holes",)})
    assert len(ours[0]["holes"]) == len(theirs[0]["holes"])
    for a, b in zip([ours[0]] + ours[0]["holes"], [theirs[0]] + theirs[0]["holes"]):
        for key in sizes:
            assert abs(a[key] - b[key]) <= 0.02 * a[key], (key, a[key], b[key])
        assert counts({k: v for k, v in a.items() if k not in sizes + ("holes",)}) == \
            counts({k: v for k, v in b.items() if k not in sizes + ("holes",)})
    assert theirs[0]["holes_filled"] > 0
    after = meshcheck(tmp_path / "saved" / "0.ply")
    before = meshcheck(shark)
    assert after["border_loops"] == before["border_loops"] - theirs[0]["holes_filled"]
    if theirs[0]["faces_added"] == ours[0]["faces_added"]:
        assert_same_geometry(tmp_path / "saved" / "server.ply", tmp_path / "saved" / "0.ply",
                             kept=before["vertices"])
    assert after["self_intersecting_pairs"] == 0


def test_measure_and_enforce_clearance(host, tmp_path):
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    tau = {"abs": 0.06}
    ours, theirs, out = run_both(host, tmp_path, [src], [
        ("meshmend_measure_clearance", {"tau": tau}),
        ("meshmend_enforce_minimum_clearance", {"tau": tau}),
        ("meshmend_measure_clearance", {"tau": tau}),
        ("meshmend_prepare_shader_view", {"values": 0})], save=tmp_path / "saved")
    # The expected differences: the double hosts store double, so nothing is
    # rounded to float; after enforcing, many pairs lie at tau to rounding,
    # and which of them measures closest depends on float or double.
    assert ours[1]["rounded_to_float"] and not theirs[1]["rounded_to_float"]
    compare(ours, theirs, out, differing={1: ("rounded_to_float",), 2: ("closest", "shortest")})
    assert theirs[0]["violating_pairs"] > 0
    assert theirs[1]["reached"] and theirs[1]["violating_pairs_after"] == 0
    after = meshcheck(tmp_path / "saved" / "0.ply", "--min-distance")
    assert after["min_distance"]["distance"] >= 0.06 * (1 - 1e-6)  # tau as pymeshlab passes it: a float
    assert theirs[2]["violating_pairs"] == 0
    assert theirs[3]["values"] == "clearance" and theirs[3]["faces"] == len(F)


def test_trim_stitch_and_close_gaps(host, tmp_path):
    nlat, nlon = 8, 12
    V, F, ring = sphere(nlat, nlon)
    ball = write_off(tmp_path / "sphere.off", V, F)
    equator = [ring(nlat // 2, j) for j in range(nlon)]
    ours, theirs, out = run_both(host, tmp_path, [ball], [
        ("meshmend_trim_along_vertex_loop", {"loop_vertices": indices(equator), "keep_side": 1,
                                             "keep_face": len(F) - 1})])
    compare(ours, theirs, out)

    A, B, pa, pb = two_sheets(7, 11)
    sheets = write_off(tmp_path / "sheets.off", *joined(A, B))
    ours, theirs, out = run_both(host, tmp_path, [sheets], [
        ("meshmend_stitch_boundaries", {"path_a": indices(pa),
                                        "path_b": indices(p + len(A[0]) for p in pb)})])
    compare(ours, theirs, out)
    assert theirs[0]["faces_added"] == 6 + 10

    require_shared_data()
    ours, theirs, out = run_both(host, tmp_path, [DATA / "stitching/quads_to_stitch.off"],
                                 [("meshmend_close_gaps", {})])
    compare(ours, theirs, out)
    assert theirs[0]["border_edges_after"] < theirs[0]["border_edges_before"]


# ---- CAD-like cases in the double hosts ------------------------------------------

def sample_params(name, step=0):
    """The parameters of a sample script's filter `step` as pymeshlab takes them."""
    convert = {"RichBool": lambda v: v == "true", "RichEnum": int, "RichMesh": int, "RichInt": int,
               "RichFloat": float, "RichString": str}
    step = ET.parse(ROOT / "samples" / name).getroot().findall("filter")[step]
    return {p.get("name"): convert[p.get("type")](p.get("value")) for p in step.iter("Param")}


def split_by_sample(host, tmp_path, inputs, sample):
    """Intersect and Split with a sample's options in the host: meshcheck on
    the merged layer as saved (binary, the host's scalar), the report, and
    the layer's description."""
    report = tmp_path / "report.json"
    params = {**sample_params(sample), "report_file": str(report)}
    out = job(host, tmp_path, inputs, [("meshmend_intersect_and_split", params)], save=tmp_path / "saved")
    assert "error" not in out["steps"][0], out["steps"][0]
    merged = next(l for l in out["layers"] if l["label"] == "intersected")
    return meshcheck(tmp_path / "saved" / f"{merged['id']}.ply"), json.loads(report.read_text()), merged


@pytest.mark.parametrize("case", sorted(cad_cases.CASES))
def test_cad_case_through_the_sample_in_the_double_host(host, tmp_path, case):
    """The CAD-like cases of tests/cad_cases.py, written in double, through
    Intersect and Split with samples/intersect_split.mlx's options: the
    double host stores the result with 0 intersecting pairs and 0
    degenerate faces by meshcheck on the saved (binary, double) layer, and
    the report's remaining_intersecting_pairs is meshcheck's count."""
    parts = cad_cases.CASES[case]()
    inputs = [write_off(tmp_path / f"part{i}.off", V, F) for i, (V, F) in enumerate(parts)]
    check, r, merged = split_by_sample(host, tmp_path, inputs, "intersect_split.mlx")
    assert check["self_intersecting_pairs"] == 0 == r["remaining_intersecting_pairs"], r
    assert check["degenerate_faces"] == 0 and check["faces"] == merged["faces"], check
    assert r["host_scalar"] == "double"


@pytest.mark.parametrize("operation", ["union", "difference"])
def test_ten_chained_booleans_in_the_double_host_stay_valid_inputs(host, tmp_path, operation):
    """Closure under repetition in the double host: the chains of
    test_patches.py (ten unions of tiles, ten holes drilled), each result the
    next split's first layer; every intermediate layer, saved as the host
    stores it, is closed, edge-manifold, free of intersecting pairs and of
    degenerate faces by meshcheck, and its report's
    remaining_intersecting_pairs is meshcheck's."""
    first, others = cad_cases.union_tiles(10) if operation == "union" else cad_cases.drill_holes(10)
    inputs = [write_off(tmp_path / f"part{i}.off", V, F) for i, (V, F) in enumerate([first] + others)]
    keep = 1 if operation == "union" else 3
    steps, reports, current = [], [], 0
    for i in range(1, 11):
        reports.append(tmp_path / f"remove{i}.json")
        steps += [("meshmend_intersect_and_split", {"mode": 1, "first_layer": current, "second_layer": i,
                                                    "output": 1, "overlaps_once": False,
                                                    "all_or_nothing": True}),
                  ("meshmend_paint_patches", {}),
                  ("meshmend_remove_patches", {"keep": keep, "report_file": str(reports[-1])})]
        current = 10 + i
    out = job(host, tmp_path, inputs, steps, save=tmp_path / "saved")
    for k, step in enumerate(out["steps"]):
        assert "error" not in step, (k, step)
    ids = {l["id"] for l in out["layers"]}
    assert ids >= set(range(11, 21)), ids
    for i, path in zip(range(11, 21), reports):
        check = meshcheck(tmp_path / "saved" / f"{i}.ply")
        report = json.loads(path.read_text())
        assert check["is_closed"] and check["non_manifold_edges"] == 0, (i, check)
        assert check["self_intersecting_pairs"] == 0 == report["remaining_intersecting_pairs"], i
        assert check["degenerate_faces"] == 0, (i, check)


CORPUS_PAIRS = [("pairs/blobby.off", "pairs/eight.off"), ("pairs/cheburashka.off", "pairs/decimated-knight.off"),
                ("pairs/cube.obj", "pairs/sphere.obj"), ("pairs/xcylinder.obj", "pairs/ycylinder.obj"),
                ("pairs/ycylinder.obj", "pairs/zcylinder.obj"), ("pairs/sphere.obj", "pairs/xcylinder.obj"),
                ("pairs/ballA.off", "pairs/ballB.off")]


@pytest.mark.parametrize("a,b", CORPUS_PAIRS, ids=[f"{a}+{b}" for a, b in CORPUS_PAIRS])
def test_corpus_pair_through_the_sample_in_the_double_host(host, tmp_path, a, b):
    """Each pair of ../shared/data through Intersect and Split with
    samples/intersect_split.mlx's options in the double host: 0 intersecting
    pairs and 0 degenerate faces by meshcheck on the saved layer, and the
    report's remaining_intersecting_pairs is meshcheck's count."""
    require_shared_data()
    check, r, _ = split_by_sample(host, tmp_path, [DATA / a, DATA / b], "intersect_split.mlx")
    assert check["self_intersecting_pairs"] == 0 == r["remaining_intersecting_pairs"], r
    assert check["degenerate_faces"] == 0, check


@pytest.mark.parametrize("a,b", CORPUS_PAIRS, ids=[f"{a}+{b}" for a, b in CORPUS_PAIRS])
def test_corpus_pair_union_in_the_double_host(host, tmp_path, a, b):
    """The union of each pair of ../shared/data in the double host
    (samples/keep_outer_surface.mlx's filters): closed and edge-manifold
    where both parts are closed, and free of intersecting pairs, by
    meshcheck on the saved layer; the report's count is meshcheck's."""
    require_shared_data()
    report = tmp_path / "report.json"
    sample = "keep_outer_surface.mlx"
    out = job(host, tmp_path, [DATA / a, DATA / b],
              [("meshmend_intersect_and_split", sample_params(sample, 0)),
               ("meshmend_paint_patches", sample_params(sample, 1)),
               ("meshmend_remove_patches", {**sample_params(sample, 2), "report_file": str(report)})],
              save=tmp_path / "saved")
    for k, step in enumerate(out["steps"]):
        assert "error" not in step, (k, step)
    union = next(l for l in out["layers"] if l["label"] == "intersected")
    check = meshcheck(tmp_path / "saved" / f"{union['id']}.ply")
    r = json.loads(report.read_text())
    assert check["self_intersecting_pairs"] == 0 == r["remaining_intersecting_pairs"], r
    if meshcheck(DATA / a)["is_closed"] and meshcheck(DATA / b)["is_closed"]:
        assert check["is_closed"] and check["non_manifold_edges"] == 0, check


@pytest.mark.parametrize("name", ["self_intersecting/cow.off", "self_intersecting/pig.off",
                                  "self_intersecting/self_intersectA.obj"])
def test_corpus_self_intersecting_mesh_through_the_sample_in_the_double_host(host, tmp_path, name):
    """Each self-intersecting mesh of ../shared/data split along its own
    curves with samples/split_self_intersections.mlx's options in the double
    host: 0 intersecting pairs by meshcheck on the saved layer, no degenerate
    face the input did not have, and the report's count is meshcheck's."""
    require_shared_data()
    check, r, _ = split_by_sample(host, tmp_path, [DATA / name], "split_self_intersections.mlx")
    assert check["self_intersecting_pairs"] == 0 == r["remaining_intersecting_pairs"], r
    assert check["degenerate_faces"] <= meshcheck(DATA / name)["degenerate_faces"], check
