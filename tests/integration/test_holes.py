"""Fill Holes (Feature Preserving) through meshlabserver: the sample script
on real meshes with holes, checked by meshcheck; selection, size limits and
bad input."""
import pytest

from conftest import DATA, ROOT, cube, meshcheck, mlx, require_shared_data, run_server, write_off

FILL = "MeshMend: Fill Holes (Feature Preserving)"
CORPUS = ["holes/holes.off", "holes/many_small_holes.ply", "holes/mech-holes-shark.off",
          "holes/face.obj", "stanford/bun_zipper.ply"]


def sample():
    text = (ROOT / "samples" / "fill_holes.mlx").read_text()
    return text.replace('name="report_file" value=""', 'name="report_file" value="{report0}"')


@pytest.mark.parametrize("name", CORPUS)
def test_holes_within_the_limits_are_closed(tmp_path, name):
    require_shared_data()
    before = meshcheck(DATA / name)
    out = tmp_path / "filled.ply"
    run = run_server(tmp_path, [DATA / name], sample(), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert r["holes_found"] >= before["border_loops"] > 0
    assert r["holes_filled"] + r["holes_skipped"] == r["holes_found"]
    # Every border edge left belongs to a hole the report says was left open.
    open_edges = sum(h["boundary_edges"] for h in r["skipped"])
    assert after["border_edges"] <= open_edges
    assert all("wider than the limit" in h["reason"] for h in r["skipped"]), r["skipped"]
    assert after["non_manifold_edges"] == before["non_manifold_edges"] == 0
    assert after["self_intersecting_pairs"] == before["self_intersecting_pairs"]
    assert r["new_intersecting_pairs"] == 0
    assert after["consistently_oriented"]
    assert after["faces"] == before["faces"] + r["faces_added"] + r["edges_split"]
    for key in ("holes_found", "holes_filled", "holes_skipped", "faces_added", "time_ms"):
        assert key in r


def test_the_bunny_is_closed_and_its_patches_follow_the_surface(tmp_path):
    require_shared_data()
    out = tmp_path / "bunny.ply"
    run = run_server(tmp_path, [DATA / "stanford/bun_zipper.ply"], sample(), outputs=[out])
    r, after = run.report, meshcheck(out)
    assert r["holes_found"] == 5 and r["holes_filled"] == 5
    assert after["is_closed"] and after["volume"] > 0
    # A patch that follows the surface stays near it: within half the widest
    # hole of the original (a patch bulging out or sinking in goes further).
    vs = meshcheck(out, "--vs", str(DATA / "stanford/bun_zipper.ply"))["vs"]
    widest = max(h["diameter"] for h in r["holes"])
    assert vs["a_to_b_max"] < 0.5 * widest, (vs, widest)
    assert vs["b_to_a_max"] < 1e-6 * after["bbox_diagonal"]  # the original surface is all there


def test_holes_at_non_manifold_edges_are_reported_and_the_rest_filled(tmp_path):
    """bun_zipper_res2 has non-manifold edges on some hole borders."""
    require_shared_data()
    out = tmp_path / "res2.ply"
    run = run_server(tmp_path, [DATA / "stanford/bun_zipper_res2.ply"], sample(), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert r["holes_skipped"] > 0 and r["holes_filled"] > 0
    for h in r["skipped"]:
        assert "non-manifold" in h["reason"] and "repair them first" in h["reason"], h
        assert f"left open: {h['reason']}" in run.log
    assert after["border_edges"] <= sum(h["boundary_edges"] for h in r["skipped"])
    assert after["self_intersecting_pairs"] == meshcheck(DATA / "stanford/bun_zipper_res2.ply")[
        "self_intersecting_pairs"]


def test_size_limit_leaves_large_holes_open(tmp_path):
    require_shared_data()
    out = tmp_path / "small_only.ply"
    script = mlx((FILL, {"max_boundary_edges": 20, "report_file": "{report0}"}))
    run = run_server(tmp_path, [DATA / "holes/many_small_holes.ply"], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    assert r["holes_skipped"] > 0 and r["holes_filled"] > 0
    for h in r["holes"]:
        assert h["filled"] == (h["boundary_edges"] <= 20), h


def test_selected_new_faces(tmp_path):
    require_shared_data()
    out = tmp_path / "selected.ply"
    script = mlx((FILL, {"select_new_faces": True, "report_file": "{report0}"})).replace(
        "</FilterScript>", ' <filter name="Delete Selected Faces"/>\n</FilterScript>')
    run = run_server(tmp_path, [DATA / "holes/mech-holes-shark.off"], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    # Deleting the selection (the patches) gives the holes back.
    after = meshcheck(out)
    before = meshcheck(DATA / "holes/mech-holes-shark.off")
    assert after["border_loops"] == before["border_loops"]


def test_no_holes_leaves_the_mesh_as_it_was(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "cube.off", V, F)
    out = tmp_path / "out.off"
    run = run_server(tmp_path, [a], mlx((FILL, {"report_file": "{report0}"})), outputs=[out])
    assert run.returncode == 0, run.log
    assert run.report["holes_found"] == 0 and run.report["faces_added"] == 0
    assert "has no holes" in run.log
    assert meshcheck(out)["faces"] == len(F)


def test_bad_input(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "open.off", V, F[1:])  # one hole
    run = run_server(tmp_path, [a], mlx((FILL, {"selected_only": True, "report_file": "{report0}"})))
    assert run.returncode != 0 and "no vertex is selected" in run.log and not run.reports
    run = run_server(tmp_path, [a], mlx((FILL, {"max_boundary_edges": -1})))
    assert run.returncode != 0 and "max hole size" in run.log
