"""Remove Self-Intersections through meshlabserver: the sample script on
real self-intersecting and non-manifold meshes, checked by meshcheck."""
import pytest

from conftest import DATA, ROOT, cube, meshcheck, require_shared_data, run_server, write_off

CORPUS = ["self_intersecting/cow.off", "self_intersecting/pig.off",
          "self_intersecting/self_intersectA.obj", "scanned/horse.ply",
          "stanford/bun_zipper_res2.ply", "stanford/bun_zipper_res3.ply",
          "stanford/bun_zipper_res4.ply", "stanford/dragon_vrip_res4.ply"]


def sample():
    text = (ROOT / "samples" / "remove_self_intersections.mlx").read_text()
    return text.replace('name="report_file" value=""', 'name="report_file" value="{report0}"')


@pytest.mark.parametrize("name", CORPUS)
def test_result_is_valid(tmp_path, name):
    require_shared_data()
    before = meshcheck(DATA / name)
    out = tmp_path / "result.ply"
    run = run_server(tmp_path, [DATA / name], sample(), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert after["self_intersecting_pairs"] == 0 == r["remaining_intersecting_pairs"]
    assert after["non_manifold_edges"] == 0 and after["non_manifold_vertices"] == 0
    assert after["consistently_oriented"]
    assert after["is_closed"] == before["is_closed"]
    assert r["faces_out"] == after["faces"] == r["faces_kept"]
    for key in ("faces_kept", "faces_removed", "components_before", "components_after", "time_ms"):
        assert key in r


def test_cow_loses_its_inverted_pockets(tmp_path):
    require_shared_data()
    out = tmp_path / "cow.ply"
    run = run_server(tmp_path, [DATA / "self_intersecting/cow.off"], sample(), outputs=[out])
    r, after = run.report, meshcheck(out)
    assert r["intersecting_pairs_before"] == 83 and r["faces_removed"] > 0
    assert r["components_before"] == r["components_after"] == 1
    assert after["is_closed"] and after["volume"] > 0


def test_inconsistent_orientation_names_the_filter_to_run(tmp_path):
    V, F = cube()
    F = [tuple(reversed(F[0]))] + F[1:]
    path = write_off(tmp_path / "flipped.off", V, F)
    out = tmp_path / "out.off"
    run = run_server(tmp_path, [path], sample(), outputs=[out])
    assert run.returncode != 0
    assert "Re-Orient all faces coherently" in run.log
    assert not run.reports
