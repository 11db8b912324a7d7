"""Remove Self-Intersections through meshlabserver: the sample script on
real self-intersecting and non-manifold meshes, checked by meshcheck, and
the volume of merged pieces against CGAL's union of the same pieces."""
import json
import math
import subprocess

import pytest

from conftest import DATA, MESHCHECK, ROOT, cube, meshcheck, need, require_shared_data, run_server, write_off

CORPUS = ["self_intersecting/cow.off", "self_intersecting/pig.off",
          "self_intersecting/self_intersectA.obj", "scanned/horse.ply",
          "stanford/bun_zipper_res2.ply", "stanford/bun_zipper_res3.ply",
          "stanford/bun_zipper_res4.ply", "stanford/dragon_vrip_res4.ply",
          "stanford/dragon_vrip_res3.ply", "stanford/dragon_vrip_res2.ply"]


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
    if r["fin_edges_before"] == 0:
        assert after["is_closed"] == before["is_closed"]
    else:  # no inside at a fin: a face there may keep a border (stated rule)
        assert after["border_edges"] - r["border_edges_before"] <= 3 * r["side_conflicts"]
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


# ---- merged pieces: the outer surface is the union -------------------------

def sphere(center, radius, rings=24, sectors=48):
    """A closed UV sphere with outward faces."""
    cx, cy, cz = center
    V = [(cx, cy, cz + radius), (cx, cy, cz - radius)]
    for i in range(1, rings):
        theta = math.pi * i / rings
        for j in range(sectors):
            phi = 2 * math.pi * j / sectors
            V.append((cx + radius * math.sin(theta) * math.cos(phi),
                      cy + radius * math.sin(theta) * math.sin(phi), cz + radius * math.cos(theta)))
    at = lambda i, j: 2 + (i - 1) * sectors + j % sectors
    F = [(0, at(1, j), at(1, j + 1)) for j in range(sectors)]
    for i in range(1, rings - 1):
        for j in range(sectors):
            F += [(at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))]
    F += [(1, at(rings - 1, j + 1), at(rings - 1, j)) for j in range(sectors)]
    return V, F


def torus(R, r, center=(0, 0, 0), around=48, tube=24):
    V = [(center[0] + (R + r * math.cos(2 * math.pi * j / tube)) * math.cos(2 * math.pi * i / around),
          center[1] + (R + r * math.cos(2 * math.pi * j / tube)) * math.sin(2 * math.pi * i / around),
          center[2] + r * math.sin(2 * math.pi * j / tube)) for i in range(around) for j in range(tube)]
    at = lambda i, j: (i % around) * tube + j % tube
    F = []
    for i in range(around):
        for j in range(tube):
            F += [(at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))]
    return V, F


def as_float(V):
    """Coordinates as MeshLab stores them, so that CGAL sees the same pieces."""
    import struct
    return [tuple(struct.unpack("f", struct.pack("f", c))[0] for c in v) for v in V]


def cgal_union_volume(tmp_path, a, b):
    peer = MESHCHECK.parent / "peer_corefine"
    need(peer.is_file(), f"{peer} (scripts/test builds it from ../shared/tools)")
    out = tmp_path / "cgal_union.off"
    run = subprocess.run([str(peer), str(a), str(b), "--out", str(out)], capture_output=True, text=True)
    report = json.loads(run.stdout)
    assert report["union"]["ok"], report
    return meshcheck(out)["volume"]


@pytest.mark.parametrize("case", ["spheres", "torus_and_sphere", "tori"])
def test_merged_pieces_have_the_volume_of_cgals_union(tmp_path, case):
    require_shared_data()
    pieces = {
        "spheres": [sphere((0, 0, 0), 1.0), sphere((0.7, 0.2, 0.1), 0.8)],
        "torus_and_sphere": [torus(1.0, 0.35), sphere((1.0, 0.0, 0.2), 0.45)],
        "tori": [torus(1.0, 0.3), torus(1.0, 0.3, center=(0.9, 0.3, 0.1))],
    }[case]
    pieces = [(as_float(V), F) for V, F in pieces]
    files = [write_off(tmp_path / f"piece{i}.off", V, F) for i, (V, F) in enumerate(pieces)]
    (Va, Fa), (Vb, Fb) = pieces
    both = write_off(tmp_path / "both.off", Va + Vb, Fa + [tuple(v + len(Va) for v in f) for f in Fb])
    out = tmp_path / "merged.ply"
    run = run_server(tmp_path, [both], sample(), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert after["self_intersecting_pairs"] == 0 and after["is_closed"] and after["consistently_oriented"]
    assert r["components_before"] == 2 and r["components_after"] == 1
    expected = cgal_union_volume(tmp_path, *files)
    assert after["volume"] == pytest.approx(expected, rel=1e-5)
    # Genus of the union: spheres 0, a sphere on a torus 1, two crossing tori 3.
    assert r["genus_after"] == {"spheres": 0, "torus_and_sphere": 1, "tori": 3}[case]
