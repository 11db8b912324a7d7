"""Patch painting, classification and removal through meshlabserver: the
sample pipelines (intersect -> paint -> classify -> remove -> weld) on real
pairs, checked by meshcheck and against CGAL's boolean volumes."""
import functools
import subprocess

import pytest

import cad_cases
from conftest import DATA, MESHCHECK, ROOT, cube, meshcheck, mlx, need, require_shared_data, run_server, \
    write_off

def shifted(V, d):
    return [(x + d, y + d, z + d) for x, y, z in V]


PAINT = "MeshMend: Paint Surface Patches"
SELECT = "MeshMend: Select Patches"
REMOVE = "MeshMend: Remove Patches"
SPLIT = "MeshMend: Intersect and Split Layers"

PAIRS = [("pairs/blobby.off", "pairs/eight.off"),
         ("pairs/ballA.off", "pairs/ballB.off"),
         ("pairs/cube.obj", "pairs/sphere.obj"),
         ("pairs/cheburashka.off", "pairs/decimated-knight.off")]
SAMPLES = {"union": "keep_outer_surface", "intersection": "keep_common_interior",
           "difference": "difference"}


def sample(name):
    """A sample script whose last report_file is {report0}."""
    text = (ROOT / "samples" / f"{name}.mlx").read_text()
    head, tail = text.rsplit('value="" name="report_file"', 1)
    return head + 'value="{report0}" name="report_file"' + tail


@functools.lru_cache(maxsize=None)
def cgal_volumes(a, b):
    """Volumes of A, B and CGAL's union (peer_corefine)."""
    peer = MESHCHECK.parent / "peer_corefine"
    need(peer.is_file(), f"{peer} (scripts/test builds it from ../shared/tools)")
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        out = f"{tmp}/union.off"
        run = subprocess.run([str(peer), str(DATA / a), str(DATA / b), "--out", out],
                             capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
        union = meshcheck(out)["volume"]
    return meshcheck(DATA / a)["volume"], meshcheck(DATA / b)["volume"], union


@pytest.mark.parametrize("operation", ["union", "intersection", "difference"])
@pytest.mark.parametrize("a,b", PAIRS)
def test_boolean_samples_match_cgal(tmp_path, a, b, operation):
    require_shared_data()
    out = tmp_path / "result.ply"
    run = run_server(tmp_path, [DATA / a, DATA / b], sample(SAMPLES[operation]), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, check = run.report, meshcheck(out)
    assert r["patches"] >= 2 and 0 < r["patches_removed"] < r["patches"]
    assert r["faces_out"] == check["faces"]
    assert r["remaining_intersecting_pairs"] == 0 and check["self_intersecting_pairs"] == 0
    assert r["non_manifold_edges"] == 0 and check["non_manifold_edges"] == 0
    assert r["border_edges"] == 0 and check["border_edges"] == 0 and check["is_closed"]
    va, vb, vu = cgal_volumes(a, b)
    vi = va + vb - vu
    expected = {"union": vu, "intersection": vi, "difference": va - vi}[operation]
    assert check["volume"] == pytest.approx(expected, rel=1e-5), (check["volume"], expected)


def test_paint_sample_lists_and_colours_patches(tmp_path):
    require_shared_data()
    out = tmp_path / "painted.ply"
    run = run_server(tmp_path, [DATA / "pairs/blobby.off", DATA / "pairs/eight.off"],
                     sample("paint_patches"), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    assert r["patches"] == len(r["patch_list"]) >= 4 and r["parts"] == 2
    assert sum(p["faces"] for p in r["patch_list"]) == meshcheck(out)["faces"]
    assert {p["part"] for p in r["patch_list"]} == {0, 1}
    # Closed parts: every patch is either inside the other part or not, clearly.
    for p in r["patch_list"]:
        other = p["winding"][1 - p["part"]]
        assert abs(other - round(other)) < 0.05
        assert ("inside part" in p["status"]) == (other > 0.5)
    assert "id   part   faces   area   status" in run.log


def test_a_mesh_without_boundaries_is_one_patch(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    run = run_server(tmp_path, [a], mlx((PAINT, {"report_file": "{report0}"})))
    assert run.returncode == 0, run.log
    assert run.report["patches"] == 1 and run.report["patch_list"][0]["faces"] == 12


def test_select_and_remove_by_hand(tmp_path):
    """Two crossing cubes: select the patches inside the union, remove them
    (moved to a layer): the rest is one closed mesh, the removed ones kept."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    out = tmp_path / "kept.ply"
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1}),
                 (PAINT, {}),
                 (SELECT, {"by": 5}),
                 (REMOVE, {"keep": 0, "removed_to_layer": True, "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script, outputs=[out])
    assert run.returncode == 0, run.log
    r = run.report
    assert r["patches"] == 4 and r["patches_removed"] == 2
    assert r["is_closed"] and r["non_manifold_edges"] == 0 and r["remaining_intersecting_pairs"] == 0
    assert r["volume"] == pytest.approx(2 - 0.125, rel=1e-6)  # two unit cubes overlapping by 1/8
    assert "layer 'removed patches'" in run.log


@pytest.mark.parametrize("offset,volumes", [
    ((0, 0, 0), {"union": 1, "intersection": 1, "difference": 0}),           # the same cube
    ((0.5, 0, 0), {"union": 1.5, "intersection": 0.5, "difference": 0.5}),   # half overlapping
    ((0.5, 0.5, 0), {"union": 1.75, "intersection": 0.25, "difference": 0.75}),
    ((1, 0, 0), {"union": 2, "intersection": 0, "difference": 1}),           # touching
    ((1, 0.5, 0), {"union": 2, "intersection": 0, "difference": 1}),         # along half a side
])
def test_booleans_of_cubes_overlapping_in_planes(tmp_path, offset, volumes):
    """CAD parts often share planes: each overlap bounds a result once (or
    not at all), and an empty result is refused with a message that says why."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", [tuple(x + d for x, d in zip(v, offset)) for v in V], F)
    for operation, volume in volumes.items():
        out = tmp_path / f"{operation}.ply"
        run = run_server(tmp_path, [a, b], sample(SAMPLES[operation]), outputs=[out])
        if volume == 0:
            assert run.returncode != 0 and "The result is empty when" in run.log, run.log[-2000:]
            continue
        assert run.returncode == 0, run.log[-3000:]
        check = meshcheck(out)
        assert check["is_closed"] and check["border_edges"] == 0, (operation, check)
        assert check["non_manifold_edges"] == 0 and check["duplicate_faces"] == 0, (operation, check)
        assert check["self_intersecting_pairs"] == 0 and check["consistently_oriented"], operation
        assert check["volume"] == pytest.approx(volume, abs=1e-6), (operation, check["volume"])


def test_booleans_of_nested_parts_and_of_a_part_inside_out(tmp_path):
    """Parts that do not cross (one inside the other) go through the three
    steps of the samples all the same; a part whose faces point inward (as
    some scans come) is taken turned, and every result faces out."""
    V, F = cube()
    outer = write_off(tmp_path / "outer.off", V, F)
    inner = write_off(tmp_path / "inner.off", [tuple(0.25 + 0.5 * x for x in v) for v in V], F)
    turned = write_off(tmp_path / "turned.off", V, [(f[0], f[2], f[1]) for f in F])
    moved = write_off(tmp_path / "moved.off", shifted(V, 0.5), F)
    cases = [((outer, inner), {"union": (1, 1), "intersection": (0.125, 1),
                               "difference": (0.875, 2)}),
             ((turned, moved), {"union": (1.875, 1), "intersection": (0.125, 1),
                                "difference": (0.875, 1)})]
    for inputs, volumes in cases:
        for operation, (volume, components) in volumes.items():
            out = tmp_path / f"{operation}.ply"
            run = run_server(tmp_path, list(inputs), sample(SAMPLES[operation]), outputs=[out])
            assert run.returncode == 0, run.log[-3000:]
            assert ("inside out" in run.log) == (inputs[0] == turned), operation
            check = meshcheck(out)
            assert check["is_closed"] and check["non_manifold_edges"] == 0, (operation, check)
            assert check["self_intersecting_pairs"] == 0 and check["consistently_oriented"]
            assert check["connected_components"] == components, (operation, check)
            assert check["volume"] == pytest.approx(volume, abs=1e-6), (operation, check["volume"])


def test_bad_input(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    # Intersection on a single part: refused, says why.
    run = run_server(tmp_path, [a], mlx((REMOVE, {"keep": 2, "report_file": "{report0}"})))
    assert run.returncode != 0 and "need two parts" in run.log and not run.reports
    # Removing the selected patches with nothing selected.
    run = run_server(tmp_path, [a], mlx((REMOVE, {"keep": 0, "report_file": "{report0}"})))
    assert run.returncode != 0 and "no face is selected" in run.log and not run.reports
    # Ids that do not exist.
    run = run_server(tmp_path, [a], mlx((SELECT, {"by": 0, "ids": "0, 4-6"})))
    assert run.returncode != 0 and "does not exist" in run.log


def test_open_layer_says_how_the_winding_number_is_thresholded(tmp_path):
    """A cube with one face missing, crossing a closed cube: classification
    works and the log explains the ½ threshold for the open part."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F[:-1])
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1}),
                 (SELECT, {"by": 2}))
    run = run_server(tmp_path, [a, b], script)
    assert run.returncode == 0, run.log
    assert "part 0 is open" in run.log and "exceeds 0.5" in run.log
    assert "selected" in run.log


def test_outer_surface_of_bunny_and_dragon(tmp_path):
    """The paper's pair: the bunny is open (five holes at its base) and the
    dragon folds through itself; the outer surface is one mesh free of
    intersections and non-manifold edges, with borders only at the bunny's
    five holes."""
    require_shared_data()
    import gzip
    import shutil
    dragon = tmp_path / "dragon_vrip.ply"
    with gzip.open(DATA / "stanford" / "dragon_vrip.ply.gz", "rb") as src, open(dragon, "wb") as dst:
        shutil.copyfileobj(src, dst)
    out = tmp_path / "union.ply"
    run = run_server(tmp_path, [DATA / "stanford" / "bun_zipper.ply", dragon],
                     sample("keep_outer_surface"), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, check = run.report, meshcheck(out)
    assert r["remaining_intersecting_pairs"] == 0 and check["self_intersecting_pairs"] == 0
    assert r["non_manifold_edges"] == 0 and check["non_manifold_edges"] == 0
    bunny = meshcheck(DATA / "stanford" / "bun_zipper.ply")
    assert check["border_loops"] == bunny["border_loops"] == 5
    assert "part 0 is open" in run.log


def test_union_of_separate_layers(tmp_path):
    """Intersect-and-split keeping the layers separate, then paint and keep
    the union of all visible layers: a new layer, the two welded into one
    closed mesh along their shared curve vertices."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    out = tmp_path / "union.ply"
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 0}),
                 (PAINT, {"layers": 1}),
                 (REMOVE, {"layers": 1, "keep": 1, "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script, outputs=[out])
    assert run.returncode == 0, run.log
    r = run.report
    assert r["patches"] == 4 and r["patches_removed"] == 2
    assert r["is_closed"] and r["non_manifold_edges"] == 0 and r["border_edges"] == 0
    assert r["remaining_intersecting_pairs"] == 0
    assert r["volume"] == pytest.approx(2 - 0.125, rel=1e-6)


def test_select_patches_touching_the_selected_faces(tmp_path):
    """A user selects a few faces of one patch (here with MeshLab's
    conditional selection on the patch id in the face quality and a
    coordinate); 'touching the selection' selects that whole patch."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1}),
                 (PAINT, {"report_file": "{report0}"}),
                 (SELECT, {"by": 1, "report_file": "{report1}"}))
    partial = ('<filter name="Conditional Face Selection">\n'
               '  <Param type="RichString" value="(fq == 2) &amp;&amp; (x0 &gt; 0.75)" '
               'name="condSelect" description="" tooltip=""/>\n </filter>\n')
    script = script.replace(f' <filter name="{SELECT}">', partial + f' <filter name="{SELECT}">', 1)
    run = run_server(tmp_path, [a, b], script)
    assert run.returncode == 0, run.log
    painted, selected = run.reports
    patch = painted["patch_list"][2]
    import re
    clicked = int(re.search(r"selected (\d+) faces in", run.log).group(1))  # MeshLab's own log
    assert 0 < clicked < patch["faces"]
    assert f"selected 1 of 4 patches ({patch['faces']} faces)" in run.log
    assert selected["patches"] == 4 and selected["patches_selected"] == 1
    assert selected["faces_selected"] == patch["faces"] and selected["selected_ids"] == [2]


def chain_steps(count, keep):
    """Steps that combine layer 0 with layers 1..count in turn: each split
    (merged) makes layer count + i, painted and cut to the boolean `keep`
    in place, and the next step takes it as its first layer."""
    steps, current = [], 0
    for i in range(1, count + 1):
        steps += [(SPLIT, {"mode": 1, "first_layer": current, "second_layer": i, "output": 1,
                           "overlaps_once": False, "all_or_nothing": True}),
                  (PAINT, {}),
                  (REMOVE, {"keep": keep, "report_file": "{report%d}" % (i - 1)})]
        current = count + i
    return steps


@pytest.mark.parametrize("operation", ["union", "difference"])
def test_ten_chained_booleans_in_the_float_host_stay_valid_inputs(tmp_path, operation):
    """Closure under repetition through MeshLab 2020.09 (float): ten unions
    of a tile with copies moved by a fraction of its size, or ten holes
    drilled one after another (tests/cad_cases.py), each result the next
    split's first layer. Every intermediate layer, as written, is closed,
    edge-manifold, free of intersecting pairs and of degenerate faces by
    meshcheck, and its report's remaining_intersecting_pairs is meshcheck's."""
    first, others = cad_cases.union_tiles(10) if operation == "union" else cad_cases.drill_holes(10)
    inputs = [write_off(tmp_path / f"part{i}.off", V, F) for i, (V, F) in enumerate([first] + others)]
    keep = 1 if operation == "union" else 3
    outputs = [(tmp_path / f"step{i}.ply", 10 + i) for i in range(1, 11)]
    run = run_server(tmp_path, inputs, mlx(*chain_steps(10, keep)), outputs=outputs)
    assert run.returncode == 0, run.log[-3000:]
    assert len(run.reports) == 10
    for (path, _), report in zip(outputs, run.reports):
        check = meshcheck(path)
        assert check["is_closed"] and check["non_manifold_edges"] == 0, (path.name, check)
        assert check["self_intersecting_pairs"] == 0 == report["remaining_intersecting_pairs"], path.name
        assert check["degenerate_faces"] == 0, (path.name, check)
    last = meshcheck(outputs[-1][0])
    if operation == "difference":  # ten through holes in one plate
        assert last["connected_components"] == 1
        assert last["vertices"] - last["edges"] + last["faces"] == 2 - 2 * 10
