"""MeshMend: Select Intersecting Faces, through the real meshlabserver."""

import pytest

from conftest import ROOT, cube, meshcheck, mlx, run_server, write_off, write_ply
import cad_cases
from shapes import tube

SELECT = "MeshMend: Select Intersecting Faces"


def shifted(V, d):
    return [(x + d, y + d, z + d) for x, y, z in V]


def test_two_overlapping_cubes_in_one_layer(tmp_path):
    V, F = cube()
    n = len(V)
    path = write_off(tmp_path / "two.off", V + shifted(V, 0.5), F + [(a + n, b + n, c + n) for a, b, c in F])
    run = run_server(tmp_path, [path], mlx((SELECT, {"mode": 0, "report_file": "{report0}"})))
    assert run.returncode == 0, run.log
    r = run.report
    assert r["self_intersecting_pairs"] == 18 and r["self_intersecting_faces"] == 12
    assert r["cross_intersecting_pairs"] == 0
    assert "selected 12 faces" in run.log


def test_between_two_layers_with_segments_layer(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    out = tmp_path / "segments.ply"
    script = mlx((SELECT, {"mode": 1, "first_layer": 0, "second_layer": 1, "segments_layer": True,
                           "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script, outputs=[out])
    assert run.returncode == 0, run.log
    assert run.report["cross_intersecting_pairs"] == 18
    assert run.report["cross_intersecting_faces_per_layer"] == [6, 6]
    assert "created layer 'intersection segments'" in run.log


def test_all_visible_layers_counts_self_and_cross(tmp_path):
    V, F = cube()
    n = len(V)
    a = write_off(tmp_path / "a.off", V + shifted(V, 0.5), F + [(x + n, y + n, z + n) for x, y, z in F])
    b = write_off(tmp_path / "b.off", shifted(V, 3.0), F)  # far away
    run = run_server(tmp_path, [a, b], mlx((SELECT, {"mode": 2, "report_file": "{report0}"})))
    assert run.returncode == 0, run.log
    assert run.report["self_intersecting_pairs_per_layer"] == [18, 0]
    assert run.report["cross_intersecting_pairs"] == 0


def test_samples_run(tmp_path):
    V, F = cube()
    a = write_ply(tmp_path / "a.ply", V, F)
    b = write_ply(tmp_path / "b.ply", shifted(V, 0.5), F)
    run = run_server(tmp_path, [a], (ROOT / "samples" / "select_intersecting.mlx").read_text())
    assert run.returncode == 0 and "0 self-intersecting pairs" in run.log, run.log
    run = run_server(tmp_path, [a, b], (ROOT / "samples" / "select_intersecting_layers.mlx").read_text())
    assert run.returncode == 0 and "18 intersecting pairs between layers" in run.log, run.log


# ---- bad input ------------------------------------------------------------

def test_same_layer_twice_is_refused(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    run = run_server(tmp_path, [a], mlx((SELECT, {"mode": 1, "first_layer": 0, "second_layer": 0,
                                                  "report_file": "{report0}"})))
    assert run.returncode != 0
    assert "chosen twice" in run.log
    assert not run.reports


def test_empty_layer_is_refused(tmp_path):
    path = tmp_path / "points.off"
    path.write_text("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n")
    run = run_server(tmp_path, [path], mlx((SELECT, {"mode": 0, "report_file": ""})))
    assert run.returncode != 0
    assert "has no faces" in run.log


def test_nan_coordinates_are_refused(tmp_path):
    path = tmp_path / "nan.off"
    path.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 1 2\n3 0 3 1\n")
    run = run_server(tmp_path, [path], mlx((SELECT, {"mode": 0, "report_file": ""})))
    assert run.returncode != 0
    assert "non-finite coordinate" in run.log


# ---- MeshMend: Intersect and Split Layers ---------------------------------

SPLIT = "MeshMend: Intersect and Split Layers"


def split_merged(tmp_path, first, second, **params):
    """Two meshes (V, F) split into one merged layer; the run and the
    written layer's path."""
    a = write_off(tmp_path / "a.off", *first)
    b = write_off(tmp_path / "b.off", *second)
    out = tmp_path / "merged.ply"  # binary float, as MeshLab holds it
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1,
                          "report_file": "{report0}", **params}))
    run = run_server(tmp_path, [a, b], script, outputs=[out])
    assert run.returncode == 0, run.log
    return run, out


def test_split_two_cubes_merged_is_free_of_intersections(tmp_path):
    V, F = cube()
    run, out = split_merged(tmp_path, (V, F), (shifted(V, 0.5), F))
    r = run.report
    assert r["remaining_intersecting_pairs"] == 0
    assert r["curve_loops"] >= 1 and r["open_curves"] == 0
    assert r["faces_split"] == 12 and r["curve_edges"] > 0
    check = meshcheck(out)
    assert check["self_intersecting_pairs"] == 0
    assert check["non_manifold_edges"] == r["curve_edges"]
    assert check["border_edges"] == 0


def test_split_keeps_layers_separate_and_closed(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    out_a, out_b = tmp_path / "a_split.off", tmp_path / "b_split.off"
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 0,
                          "report_file": "{report0}"}),
                 ("MeshMend: Inspect Mesh Defects", {"report_file": "{report1}"}))
    run = run_server(tmp_path, [a, b], script)
    assert run.returncode == 0, run.log
    inspect = run.reports[1]  # the current layer after the split: b, in place
    assert inspect["is_closed"] and inspect["non_manifold_edges"] == 0
    assert inspect["faces"] > 12


def test_split_of_layers_that_do_not_intersect_succeeds_unchanged(tmp_path):
    """Kept separate, layers that do not meet have nothing to split: that is
    success (MeshLab's convention), logged and reported, the layers as they
    were. Merged, the merged layer holds them as they are (the boolean
    filters take nested or separate parts from it)."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 5.0), F)
    kept = tmp_path / "b_kept.ply"
    run = run_server(tmp_path, [a, b], mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1,
                                                    "output": 0, "report_file": "{report0}"})),
                     outputs=[kept])
    assert run.returncode == 0, run.log[-2000:]
    assert "do not intersect" in run.log and "merged output" in run.log and "unchanged" in run.log
    assert run.report["unchanged"] and run.report["intersecting_pairs"] == 0
    check = meshcheck(kept)
    assert check["faces"] == 12 and check["bbox"][0] == 5.0  # layer b as it was
    out = tmp_path / "merged.ply"
    run = run_server(tmp_path, [a, b], mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1,
                                                    "output": 1, "report_file": "{report0}"})),
                     outputs=[out])
    assert run.returncode == 0, run.log
    assert "do not intersect" in run.log and "smallest angle" not in run.log
    assert run.report["intersecting_pairs"] == 0 and run.report["faces_split"] == 0
    check = meshcheck(out)
    assert check["faces"] == 24 and check["connected_components"] == 2
    assert check["is_closed"] and check["self_intersecting_pairs"] == 0


def test_split_refuses_a_bad_snapping_tolerance(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    out = tmp_path / "b_out.off"
    for tolerance in (-0.1, 0.7):
        script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 0,
                              "snap_tolerance": tolerance, "report_file": "{report0}"}))
        run = run_server(tmp_path, [a, b], script, outputs=[out])
        assert run.returncode != 0
        assert "snapping tolerance" in run.log and not run.reports


def test_split_with_snapping_on_two_cubes(tmp_path):
    """Cubes offset by a hair: the curves pass 1e-4 from the corners and make
    slivers, which snapping removes; the result stays free of intersections."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", [(x + 0.5, y + 0.5001, z + 0.4999) for x, y, z in V], F)
    out = tmp_path / "merged.ply"  # binary float, as MeshLab holds it
    results = {}
    for tolerance in (0, 0.05):
        script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1,
                              "snap_tolerance": tolerance, "report_file": "{report0}"}))
        run = run_server(tmp_path, [a, b], script, outputs=[out])
        assert run.returncode == 0, run.log
        results[tolerance] = run.report
        assert run.report["remaining_intersecting_pairs"] == 0
        check = meshcheck(out)
        assert check["self_intersecting_pairs"] == 0
        assert check["non_manifold_edges"] == run.report["curve_edges"]
        assert check["border_edges"] == 0
    plain, snapped = results[0], results[0.05]
    assert plain["vertices_snapped"] == 0 and snapped["vertices_snapped"] > 0
    assert snapped["smallest_new_angle_deg_unsnapped"] == plain["smallest_new_angle_deg"]
    assert snapped["smallest_new_angle_deg"] > 10 * plain["smallest_new_angle_deg"]
    assert snapped["new_faces_below_1deg"] < plain["new_faces_below_1deg"]


def test_split_of_a_mesh_and_itself_keeps_one_surface(tmp_path):
    """The same cube in two layers overlaps itself everywhere: merged, it is
    there once, closed, with nothing crossing and no duplicate face."""
    run, out = split_merged(tmp_path, cube(), cube(), overlaps_once=True)
    assert run.report["coincident_faces_removed"] == 12
    assert run.report["remaining_intersecting_pairs"] == 0
    assert "keeps each once" in run.log
    check = meshcheck(out)
    assert check["faces"] == 12 and check["duplicate_faces"] == 0
    assert check["self_intersecting_pairs"] == 0 and check["border_edges"] == 0


def test_separate_layers_overlapping_in_planes_keep_their_faces_uncounted(tmp_path):
    """A cube and the same cube moved by half its width, kept as separate
    layers: where their sides overlap in a plane each layer keeps its own
    faces. Those coincide (the same three vertices once welded) and are no
    crossing: the check reports none and the float result is not split
    again; each layer is its own closed surface."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", [(x + 0.5, y, z) for x, y, z in V], F)
    layers = [tmp_path / "a_out.ply", tmp_path / "b_out.ply"]
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 0,
                          "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script, outputs=[(layers[0], 0), (layers[1], 1)])
    assert run.returncode == 0, run.log
    r = run.report
    assert r["coincident_faces"] > 0 and "lie in two layers" in run.log
    assert r["remaining_intersecting_pairs"] == 0 and r["pairs_split_after_rounding"] == 0
    assert not r["snapped_for_host"] and "snapping tolerance" not in run.log
    for layer in layers:
        check = meshcheck(layer)
        assert check["self_intersecting_pairs"] == 0 and check["is_closed"]
        assert check["non_manifold_edges"] == 0 and check["duplicate_faces"] == 0


def test_split_of_tangent_tubes_is_free_of_intersections_as_float(tmp_path):
    """Two tubes of one radius crossing at right angles touch tangentially:
    curve points there lie far closer than a float step. The float result
    is repaired (points merged, what still crosses split again): nothing
    crosses, nothing collapses."""
    run, out = split_merged(tmp_path, tube(0), tube(1))
    r = run.report
    assert r["remaining_intersecting_pairs"] == 0 and r["degenerate_new_faces"] == 0
    assert r["snapped_for_host"] or r["pairs_split_after_rounding"] > 0
    check = meshcheck(out)
    assert check["self_intersecting_pairs"] == 0 and check["degenerate_faces"] == 0
    assert check["border_edges"] == 0


def test_separate_layers_of_tangent_tubes_are_repaired_as_float(tmp_path):
    """The same tubes kept as separate layers: the repair of the float
    result reaches each layer (what MeshLab stores), not only a merged one."""
    a = write_off(tmp_path / "a.off", *tube(0))
    b = write_off(tmp_path / "b.off", *tube(1))
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 0,
                          "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script)
    assert run.returncode == 0, run.log
    r = run.report
    assert r["output"] == "separate" and r["pairs_split_after_rounding"] > 0
    assert r["remaining_intersecting_pairs"] == 0 and r["degenerate_new_faces"] == 0


def test_split_of_a_layer_that_meets_itself_only_through_duplicates(tmp_path):
    """A cube listed twice in one layer (its own vertices each time): welded,
    the second copy is duplicate faces; removing them is the whole repair,
    and the result is written."""
    V, F = cube()
    path = write_off(tmp_path / "twice.off", V + V, F + [(a + 8, b + 8, c + 8) for a, b, c in F])
    out = tmp_path / "out.ply"
    script = mlx((SPLIT, {"mode": 0, "first_layer": 0, "second_layer": 0, "output": 1,
                          "weld_duplicate_vertices": True, "remove_duplicate_faces": True,
                          "report_file": "{report0}"}))
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log
    assert run.report["vertices_welded"] == 8 and run.report["duplicate_faces_removed"] == 12
    check = meshcheck(out)
    assert check["faces"] == 12 and check["self_intersecting_pairs"] == 0


def test_split_refuses_a_layer_whose_faces_all_collapse(tmp_path):
    """A unit cube at 1e8, where a float step is 8: as MeshLab stores it, all
    its corners are one point."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", [(x + 1e8, y + 1e8, z + 1e8) for x, y, z in V], F)
    b = write_off(tmp_path / "b.off", [(x + 1e8 + 0.5, y + 1e8, z + 1e8) for x, y, z in V], F)
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1,
                          "weld_duplicate_vertices": True, "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script)
    assert run.returncode != 0 and not run.reports
    assert "no face with three corners at distinct positions" in run.log and "near the origin" in run.log


def test_split_sample_runs(tmp_path):
    V, F = cube()
    a = write_ply(tmp_path / "a.ply", V, F)
    b = write_ply(tmp_path / "b.ply", shifted(V, 0.5), F)
    run = run_server(tmp_path, [a, b], (ROOT / "samples" / "intersect_split.mlx").read_text())
    assert run.returncode == 0, run.log
    assert "0 intersecting pairs remain" in run.log


def test_split_self_intersections_sample_on_a_clean_mesh_succeeds_unchanged(tmp_path):
    """Nothing to split is success: the sample script does not stop a batch
    on a mesh that does not intersect itself, and the layer stays as it was."""
    V, F = cube()
    src = write_off(tmp_path / "cube.off", V, F)
    out = tmp_path / "out.ply"
    text = (ROOT / "samples" / "split_self_intersections.mlx").read_text()
    run = run_server(tmp_path, [src], text, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    assert "does not intersect itself" in run.log and "unchanged" in run.log
    check = meshcheck(out)
    assert check["faces"] == 12 and check["vertices"] == 8 and check["volume"] == 1


def test_split_in_a_float_host_names_detail_that_float_storage_rounds(tmp_path):
    """A part at 20,000 whose detail spans a few float steps (2 mm at 2e4:
    about one float step, 0.002): MeshLab 2020.09 stores it in float on
    loading, and the split's log and report say so for that layer only."""
    V, F = cube()
    fine = [(2e4 + 0.002 * x, 2e4 + y, 2e4 + z) for x, y, z in V]
    coarse = [(2e4 + x - 0.5, 2e4 + y - 0.5, 2e4 + z - 0.5) for x, y, z in V]
    run, _ = split_merged(tmp_path, (fine, F), (coarse, F))
    notes = run.report.get("float_storage_notes", [])
    assert len(notes) == 1, run.log
    assert "float steps" in notes[0] and "double host" in notes[0]
    assert "warning:" in run.log and "float steps" in run.log
    # Ordinary detail: no note.
    run, _ = split_merged(tmp_path, (V, F), (shifted(V, 0.5), F))
    assert "float_storage_notes" not in run.report


@pytest.mark.parametrize("case", sorted(cad_cases.CASES))
def test_cad_case_through_the_sample_in_the_float_host(tmp_path, case):
    """The CAD-like cases of tests/cad_cases.py (written in double; MeshLab
    2020.09 stores them in float on loading) through
    samples/intersect_split.mlx: the written layer has 0 intersecting pairs
    and 0 degenerate faces by meshcheck, and the report's
    remaining_intersecting_pairs is meshcheck's count; or the filter
    refuses ('All or nothing' is on in the sample), saying why, and writes
    nothing."""
    parts = cad_cases.CASES[case]()
    inputs = [write_off(tmp_path / f"part{i}.off", V, F) for i, (V, F) in enumerate(parts)]
    script = (ROOT / "samples" / "intersect_split.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"')
    out = tmp_path / "merged.ply"
    run = run_server(tmp_path, inputs, script, outputs=[out])
    if run.returncode != 0:
        assert "All or nothing" in run.log and "left unchanged" in run.log, run.log[-2000:]
        assert not out.exists()
        return
    check = meshcheck(out)
    assert check["self_intersecting_pairs"] == 0 == run.report["remaining_intersecting_pairs"], run.report
    assert check["degenerate_faces"] == 0, check
