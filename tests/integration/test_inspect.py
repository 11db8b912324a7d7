"""MeshMend: Inspect Mesh Defects, through the real meshlabserver."""
import pytest

from conftest import ROOT, WRITERS, cube, meshcheck, mlx, require_shared_data, run_server, write_off

INSPECT = "MeshMend: Inspect Mesh Defects"


@pytest.mark.parametrize("fmt", ["off", "ply", "obj", "stl"])
def test_every_format_reports_the_defects(tmp_path, fmt):
    V, F = cube()
    F = F[1:]  # one triangle missing: a hole of 3 border edges
    path = WRITERS[fmt](tmp_path / f"open_cube.{fmt}", V, F)
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "{report0}"})))
    assert run.returncode == 0, run.log
    r = run.report
    assert r["faces"] == 11
    assert r["border_edges"] == 3 and r["border_loops"] == 1
    assert r["is_closed"] is False and r["volume"] is None
    assert r["connected_components"] == 1
    assert "MeshMend inspect of layer" in run.log and "3 border edges in 1 loops" in run.log
    if fmt == "stl":  # 3 vertices per facet in the file, unified by MeshLab
        assert r["file_vertices"] == 33 and r["vertices"] == 8
        assert any("unified" in n for n in r["importer_notes"])
    else:
        assert r["vertices"] == 8 and r["importer_notes"] == []
        assert r["file_faces"] == 11


def test_closed_cube_volume_and_genus(tmp_path):
    V, F = cube()
    path = write_off(tmp_path / "cube.off", [(2 * x, 3 * y, 4 * z) for x, y, z in V], F)
    r = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "{report0}"}))).report
    assert r["is_closed"] and r["consistently_oriented"]
    assert r["volume"] == pytest.approx(24.0, rel=1e-12)
    assert r["genus"] == 0 and r["euler_characteristic"] == 2
    assert r["time_ms"] >= 0


def test_sample_script_prints_the_report(tmp_path):
    V, F = cube()
    path = write_off(tmp_path / "cube.off", V, F[:-1])
    run = run_server(tmp_path, [path], (ROOT / "samples" / "inspect.mlx").read_text())
    assert run.returncode == 0, run.log
    assert "vertices 8, faces 11" in run.log
    assert "border edges 3 in 1 border loops" in run.log


def test_counts_agree_with_meshcheck_on_a_defective_soup(tmp_path):
    # Non-manifold fin, flipped face, duplicate face, unreferenced and duplicate points.
    require_shared_data()  # meshcheck is built from ../shared/tools
    V, F = cube()
    V = V + [(0.5, -1, 0.5), (9, 9, 9), (1, 1, 1)]
    F = F + [(0, 1, 8), (F[3][0], F[3][2], F[3][1]), F[5]]
    path = write_off(tmp_path / "soup.off", V, F)
    ours = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "{report0}"}))).report
    theirs = meshcheck(path)
    for key in ["vertices", "faces", "connected_components", "border_edges", "border_loops",
                "non_manifold_edges", "non_manifold_vertices", "degenerate_faces", "duplicate_faces",
                "isolated_vertices", "duplicate_points", "is_closed", "consistently_oriented",
                "orientation_inconsistent_edges", "volume"]:
        assert ours[key] == theirs[key], key


def test_selecting_border_defects(tmp_path):
    V, F = cube()
    path = write_off(tmp_path / "open.off", V, F[1:])
    run = run_server(tmp_path, [path], mlx((INSPECT, {"select_defects": 3, "report_file": ""})))
    assert run.returncode == 0, run.log
    assert "selected 3 faces and 3 vertices" in run.log


# ---- bad input ------------------------------------------------------------

def test_empty_file_is_refused_by_the_loader_without_crash(tmp_path):
    path = tmp_path / "empty.off"
    path.write_text("")
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": ""})))
    assert run.returncode != 0
    assert "Failed loading" in run.log
    assert "Segmentation" not in run.log and "Aborted" not in run.log


def test_nan_coordinates_are_reported(tmp_path):
    path = tmp_path / "nan.off"
    path.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 1 2\n3 0 3 1\n")
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "{report0}"})))
    assert run.returncode == 0, run.log
    assert run.report["non_finite_vertices"] == 1
    assert "1 vertices with NaN or infinite coordinates" in run.log


def test_face_index_out_of_range_gives_a_clear_message(tmp_path):
    path = tmp_path / "bad_index.off"
    path.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "{report0}"})))
    assert run.returncode != 0
    assert "refers to a vertex that does not exist" in run.log
    assert not run.reports  # nothing half-written


def test_obj_index_out_of_range_is_refused_by_the_importer(tmp_path):
    path = tmp_path / "bad_index.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": ""})))
    assert run.returncode != 0
    assert "refers to vertex 7, but the file has 3" in run.log


def test_unwritable_report_file_fails_with_the_path(tmp_path):
    V, F = cube()
    path = write_off(tmp_path / "cube.off", V, F)
    run = run_server(tmp_path, [path], mlx((INSPECT, {"report_file": "/nonexistent-dir/r.json"})))
    assert run.returncode != 0
    assert "/nonexistent-dir/r.json" in run.log
