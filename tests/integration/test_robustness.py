"""Every MeshMend filter on the generated classes of tests/robustness_shapes.py
(coordinates from 1e-30 to near FLT_MAX, coplanar contact between parts,
non-manifold and inconsistently oriented exports, STL soups with
T-junctions, walls with holes, spindle and self-touching tori, an
OpenSCAD-like export), with its defaults, through meshlabserver (MeshLab
2020.09, float) and real pymeshlab 2025.7 (double): each run ends within a
minute, and either succeeds with an output that meets the filter's
contract by meshcheck, or refuses with a MeshMend error that leaves the
layer as it was (pymeshlab, where the layer can be saved after the error)."""
import json
import sys
import time

import numpy as np
import pytest

from conftest import (BUILD, ROOT, Host, meshcheck, mlx, need, read_ply, require_meshcheck,
                      run_server, write_ply)

sys.path.append(str(ROOT / "tests"))
import robustness_shapes  # noqa: E402

CLASSES = robustness_shapes.classes()
REMOVE = "MeshMend: Remove Self-Intersections"
SPLIT = "MeshMend: Intersect and Split Layers"
FILL = "MeshMend: Fill Holes (Feature Preserving)"
CLOSE = "MeshMend: Close Gaps Between Borders"
ENFORCE = "MeshMend: Enforce Minimum Clearance"
MEASURE = "MeshMend: Measure Clearance"
READ_ONLY = ["MeshMend: Inspect Mesh Defects", "MeshMend: Select Intersecting Faces",
             "MeshMend: Paint Surface Patches", MEASURE]
EDITING = [REMOVE, SPLIT, FILL, CLOSE, ENFORCE, "MeshMend: Trim Along Vertex Loop",
           "MeshMend: Stitch Boundaries"]
PYTHON = {"MeshMend: Inspect Mesh Defects": "meshmend_inspect_defects",
          "MeshMend: Select Intersecting Faces": "meshmend_select_intersecting_faces",
          "MeshMend: Paint Surface Patches": "meshmend_paint_patches",
          MEASURE: "meshmend_measure_clearance", REMOVE: "meshmend_remove_self_intersections",
          SPLIT: "meshmend_intersect_and_split", FILL: "meshmend_fill_holes",
          CLOSE: "meshmend_close_gaps", ENFORCE: "meshmend_enforce_minimum_clearance",
          "MeshMend: Trim Along Vertex Loop": "meshmend_trim_along_vertex_loop",
          "MeshMend: Stitch Boundaries": "meshmend_stitch_boundaries"}
SECONDS = 60  # every run ends within this, or is stopped by its bound


def tau_of(V):
    V = np.asarray(V, float)
    return float(0.005 * np.linalg.norm(V.max(0) - V.min(0)))


def params(name, V):
    """The filter's parameters here: its defaults, a report, and a tau."""
    p = {"report_file": "{report0}"}
    if name in (ENFORCE, MEASURE):
        p["tau"] = tau_of(V)
    return p


def check_contract(name, before, after, report):
    """What the filter's output must be (by meshcheck), given the input's."""
    if name == REMOVE:
        assert after["self_intersecting_pairs"] == 0 and after["non_manifold_edges"] == 0
        assert after["non_manifold_vertices"] == 0 and after["consistently_oriented"]
        if report.get("input_closed") and report.get("fin_edges_before") == 0:
            assert after["is_closed"]
    elif name == CLOSE:
        assert after["non_manifold_edges"] <= before["non_manifold_edges"]
        assert after["self_intersecting_pairs"] <= before["self_intersecting_pairs"]
    elif name == ENFORCE:
        assert after["self_intersecting_pairs"] == 0
    elif name == FILL:
        assert after["border_edges"] <= before["border_edges"]
        assert after["non_manifold_edges"] <= before["non_manifold_edges"]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    require_meshcheck()
    folder = tmp_path_factory.mktemp("classes")
    return {name: write_ply(folder / f"{name}.ply", V, F) for name, (V, F) in CLASSES.items()}


@pytest.fixture(scope="module")
def as_loaded(inputs, tmp_path_factory):
    """Each class as meshlabserver loads and saves it with no filter."""
    out = {}
    for name, path in inputs.items():
        folder = tmp_path_factory.mktemp(name)
        saved = folder / "loaded.ply"
        run = run_server(folder, [path], mlx(("MeshMend: Inspect Mesh Defects", {})), outputs=[saved])
        assert run.returncode == 0, run.log[-2000:]
        out[name] = saved
    return out


def classify(run, seconds):
    """'valid', or 'refused' with its message; anything else fails."""
    assert seconds < SECONDS, f"took {seconds:.0f} s"
    if run.returncode == 0:
        return "valid"
    assert "MeshMend error:" in run.log, run.log[-3000:]
    assert "internal error" not in run.log, run.log[-3000:]
    return "refused"


@pytest.mark.parametrize("name", list(CLASSES))
@pytest.mark.parametrize("filter_name", READ_ONLY + EDITING)
def test_meshlabserver(tmp_path, inputs, as_loaded, name, filter_name):
    V, _ = CLASSES[name]
    out = tmp_path / "out.ply"
    start = time.monotonic()
    run = run_server(tmp_path, [inputs[name]], mlx((filter_name, params(filter_name, V))),
                     outputs=[out], timeout=SECONDS * 3)
    outcome = classify(run, time.monotonic() - start)
    print(f"{name} | {filter_name} | {outcome} | {time.monotonic() - start:.1f} s")
    if outcome == "refused":
        return
    report = run.reports[-1] if run.reports else {}
    loaded = read_ply(as_loaded[name])
    result = read_ply(out)
    if filter_name in READ_ONLY or report.get("unchanged"):
        # The geometry is the layer's as it was.
        np.testing.assert_array_equal(result[0], loaded[0])
        np.testing.assert_array_equal(result[1], loaded[1])
        return
    check_contract(filter_name, meshcheck(as_loaded[name]), meshcheck(out), report)


# ---- the double host: real pymeshlab 2025.7 ---------------------------------

@pytest.fixture(scope="module")
def double_host():
    h = Host("2025.07d")
    h.require_pymeshlab()
    return h


def job(host, tmp_path, mesh, steps):
    return host.pymeshlab_job({"plugins": [str(p) for p in host.plugins], "meshes": [str(mesh)],
                               "steps": [{"filter": f, "params": p} for f, p in steps],
                               "save": str(tmp_path / "saved"), "describe": []}, tmp_path,
                              timeout=SECONDS * 3)


@pytest.mark.parametrize("name", list(CLASSES))
@pytest.mark.parametrize("filter_name", [REMOVE, SPLIT, FILL, CLOSE, ENFORCE])
def test_double_host(tmp_path, double_host, inputs, name, filter_name):
    V, _ = CLASSES[name]
    p = {k: v for k, v in params(filter_name, V).items() if k != "report_file"}
    if "tau" in p:
        p["tau"] = {"abs": p["tau"]}
    (tmp_path / "before").mkdir()
    baseline = job(double_host, tmp_path / "before", inputs[name], [])
    start = time.monotonic()
    result = job(double_host, tmp_path, inputs[name], [(PYTHON[filter_name], p)])
    seconds = time.monotonic() - start
    assert seconds < SECONDS, f"took {seconds:.0f} s"
    step = result["steps"][0]
    before = read_ply(tmp_path / "before" / "saved" / "0.ply")
    after = read_ply(tmp_path / "saved" / "0.ply")
    if "error" in step:
        print(f"{name} | {filter_name} | refused | {seconds:.1f} s | {step['error'][:120]}")
        assert "internal error" not in step["error"]
        # A refusal leaves the layer as it was.
        np.testing.assert_array_equal(after[0], before[0])
        np.testing.assert_array_equal(after[1], before[1])
        return
    print(f"{name} | {filter_name} | valid | {seconds:.1f} s")
    report = step["result"]
    if report.get("unchanged"):
        np.testing.assert_array_equal(after[0], before[0])
        np.testing.assert_array_equal(after[1], before[1])
        return
    check_contract(filter_name, meshcheck(tmp_path / "before" / "saved" / "0.ply"),
                   meshcheck(tmp_path / "saved" / "0.ply"), report)
