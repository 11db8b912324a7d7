"""Trim Along Vertex Loop, Stitch Boundaries and Close Gaps Between Borders
through meshlabserver, checked by meshcheck: a closed mesh trimmed along an
index-list loop, bad loops, open sheets stitched across a gap (one layer,
two layers, selections, junctions), gap closing on the stitching corpus and
the STL soups against CGAL's stitch_borders (peer_stitch), and a trim and
stitch assembly of two aligned range scans."""
import json
import math
import re
import struct
import subprocess

import numpy as np
import pytest

from conftest import (BUILD, DATA, ROOT, meshcheck, mlx, read_ply, require_shared_data,
                      run_server, write_off)
from range_scan_assembly import assemble, main_component

TRIM = "MeshMend: Trim Along Vertex Loop"
STITCH = "MeshMend: Stitch Boundaries"
CLOSE = "MeshMend: Close Gaps Between Borders"
PEER_STITCH = BUILD / "shared-tools" / "peer_stitch"
REPORT_KEYS = ("border_edges_before", "border_edges_after", "faces_added", "vertices_merged",
               "time_ms")


def sample(name):
    text = (ROOT / "samples" / name).read_text()
    return text.replace('name="report_file" value=""', 'name="report_file" value="{report0}"')


def condition(kind, expression):
    """A MeshLab conditional selection step (how a script selects)."""
    expression = expression.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return (f' <filter name="Conditional {kind} Selection">\n'
            f'  <Param type="RichString" value="{expression}" name="condSelect" description="" '
            f'tooltip=""/>\n </filter>\n')


def before(script, name, steps):
    return script.replace(f' <filter name="{name}">', "".join(steps) + f' <filter name="{name}">', 1)


# ---- meshes -------------------------------------------------------------------

def sphere(nlat=8, nlon=12):
    """A closed latitude-longitude sphere, outward oriented; ring i (1..nlat-1)
    holds vertices 1 + (i-1)*nlon + j, the poles are first and last."""
    V = [(0.0, 1.0, 0.0)]
    for i in range(1, nlat):
        t = math.pi * i / nlat
        for j in range(nlon):
            p = 2 * math.pi * j / nlon
            V.append((math.sin(t) * math.cos(p), math.cos(t), math.sin(t) * math.sin(p)))
    V.append((0.0, -1.0, 0.0))
    ring = lambda i, j: 1 + (i - 1) * nlon + j % nlon
    south = len(V) - 1
    F = [(0, ring(1, j + 1), ring(1, j)) for j in range(nlon)]
    for i in range(1, nlat - 1):
        for j in range(nlon):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)
            F += [(a, b, c), (a, c, d)]
    F += [(south, ring(nlat - 1, j), ring(nlat - 1, j + 1)) for j in range(nlon)]
    def det(a, b, c):
        return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                a[2] * (b[0] * c[1] - b[1] * c[0]))
    volume = sum(det(V[a], V[b], V[c]) for a, b, c in F)
    if volume < 0:
        F = [(a, c, b) for a, b, c in F]
    return V, F, ring


def sheet(n, x0, x1, z=lambda x, y: 0.0, rows=None):
    """A grid sheet of n columns x `rows` rows over [x0, x1] x [0, 1], normals
    up (+z); vertex (i, j) is i * rows + j."""
    rows = rows or n
    V = [(x0 + (x1 - x0) * i / (n - 1), j / (rows - 1), 0.0) for i in range(n) for j in range(rows)]
    V = [(x, y, z(x, y)) for x, y, _ in V]
    F = []
    for i in range(n - 1):
        for j in range(rows - 1):
            a, b, c, d = i * rows + j, (i + 1) * rows + j, (i + 1) * rows + j + 1, i * rows + j + 1
            F += [(a, b, c), (a, c, d)]
    return V, F


def joined(*meshes):
    V, F = [], []
    for v, f in meshes:
        F += [tuple(i + len(V) for i in t) for t in f]
        V += v
    return V, F


def indices(xs):
    return " ".join(map(str, xs))


def expect_clean(check):
    assert check["non_manifold_edges"] == 0 and check["non_manifold_vertices"] == 0, check
    assert check["consistently_oriented"] and check["orientation_inconsistent_edges"] == 0, check
    assert check["self_intersecting_pairs"] == 0 and check["degenerate_faces"] == 0, check


# ---- trimming -----------------------------------------------------------------

def test_trim_a_closed_mesh_along_an_index_loop_keeping_a_face(tmp_path):
    nlat, nlon = 8, 12
    V, F, ring = sphere(nlat, nlon)
    path = write_off(tmp_path / "sphere.off", V, F)
    equator = [ring(nlat // 2, j) for j in range(nlon)]
    south_face = len(F) - 1
    out = tmp_path / "south.ply"
    script = mlx((TRIM, {"loop_vertices": indices(equator), "keep_side": 1,
                         "keep_face": south_face, "removed_to_layer": True,
                         "report_file": "{report0}"}))
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    half = nlon + (nlat // 2 - 1) * 2 * nlon  # a cap and the rows down to the equator
    assert r["faces_kept"] == after["faces"] == half
    assert r["faces_removed"] == len(F) - half
    assert r["border_edges_before"] == 0
    assert r["border_edges_after"] == after["border_edges"] == len(equator)
    assert after["border_loops"] == 1 and after["connected_components"] == 1
    assert after["vertices"] == 1 + (nlat // 2) * nlon  # the north's vertices are gone
    assert after["bbox"][4] <= 1e-6  # every kept vertex is at or below the equator
    expect_clean(after)
    for key in REPORT_KEYS:
        assert key in r
    assert r["faces_added"] == 0 and r["vertices_merged"] == 0
    assert "trimmed layer" in run.log and "loop of 12 vertices" in run.log


def test_trim_by_the_loop_direction_and_reversed(tmp_path):
    nlat, nlon = 6, 10
    V, F, ring = sphere(nlat, nlon)
    path = write_off(tmp_path / "sphere.off", V, F)
    loop = [ring(2, j) for j in range(nlon)]  # the northern ring: caps of different sizes
    kept = []
    for order in (loop, loop[::-1]):
        out = tmp_path / "out.ply"
        run = run_server(tmp_path, [path], mlx((TRIM, {"loop_vertices": indices(order),
                                                       "keep_side": 2,
                                                       "report_file": "{report0}"})),
                         outputs=[out])
        assert run.returncode == 0, run.log[-3000:]
        kept.append(run.report["faces_kept"])
        expect_clean(meshcheck(out))
    assert sorted(kept) == [nlon + 2 * nlon, len(F) - 3 * nlon]  # one side each way


def test_trim_by_selected_vertices_and_one_selected_face(tmp_path):
    """What a GUI user does: the loop's vertices selected, and one face on the
    side to keep (here with MeshLab's conditional selections)."""
    nlat, nlon = 8, 12
    V, F, ring = sphere(nlat, nlon)
    path = write_off(tmp_path / "sphere.off", V, F)
    out = tmp_path / "north.ply"
    script = before(mlx((TRIM, {"report_file": "{report0}"})), TRIM, [
        condition("Vertex", "abs(y) < 0.0001"),
        condition("Face", "(y0 > 0.999) || (y1 > 0.999) || (y2 > 0.999)"),  # the north cap
    ])
    run = run_server(tmp_path, [path], script, outputs=[out])
    # The whole cap is selected: not exactly one face.
    assert run.returncode != 0 and f"{nlon} faces are selected" in run.log, run.log[-2000:]
    one = "(y0 > 0.999) && (x1 + x2 > 0.2) && (z1 + z2 > 0.05) && (z1 + z2 < 0.4)"
    script = before(mlx((TRIM, {"report_file": "{report0}"})), TRIM, [
        condition("Vertex", "abs(y) < 0.0001"), condition("Face", one)])
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    after = meshcheck(out)
    assert after["faces"] == nlon + (nlat // 2 - 1) * 2 * nlon
    assert after["bbox"][1] >= -1e-6  # the northern half
    assert after["border_edges"] == nlon
    expect_clean(after)


def test_not_a_loop_says_where_it_breaks_and_leaves_the_layer(tmp_path):
    nlat, nlon = 8, 12
    V, F, ring = sphere(nlat, nlon)
    path = write_off(tmp_path / "sphere.off", V, F)
    equator = [ring(nlat // 2, j) for j in range(nlon)]
    gap = equator[:5] + equator[6:]  # skips one vertex: 4 and 6 share no edge
    out = tmp_path / "out.ply"
    run = run_server(tmp_path, [path], mlx((TRIM, {"loop_vertices": indices(gap), "keep_side": 1,
                                                   "keep_face": 0, "report_file": "{report0}"})),
                     outputs=[out])
    assert run.returncode != 0 and not run.reports
    assert (f"the loop is broken between vertex {equator[4]}" in run.log and
            f"and vertex {equator[6]}" in run.log), run.log[-2000:]
    # A selection that stops: the path ends at a named vertex.
    script = before(mlx((TRIM, {"keep_side": 1, "keep_face": 0, "report_file": "{report0}"})), TRIM,
                    [condition("Vertex", "(abs(y) < 0.0001) && (z > -0.1)")])
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode != 0 and not run.reports
    assert re.search(r"the selection is not a closed loop: the path ends at vertex \d+ \(", run.log)


def test_loop_around_a_handle_does_not_separate(tmp_path):
    """A torus: a meridian loop around the tube leaves one connected side."""
    n, m = 16, 8
    V = []
    for i in range(n):
        u = 2 * math.pi * i / n
        for j in range(m):
            w = 2 * math.pi * j / m
            V.append(((2 + 0.5 * math.cos(w)) * math.cos(u), (2 + 0.5 * math.cos(w)) * math.sin(u),
                      0.5 * math.sin(w)))
    idx = lambda i, j: (i % n) * m + j % m
    F = []
    for i in range(n):
        for j in range(m):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            F += [(a, b, c), (a, c, d)]
    path = write_off(tmp_path / "torus.off", V, F)
    out = tmp_path / "out.ply"
    run = run_server(tmp_path, [path], mlx((TRIM, {"loop_vertices": indices(idx(0, j) for j in range(m)),
                                                   "keep_side": 1, "keep_face": 0,
                                                   "report_file": "{report0}"})), outputs=[out])
    assert run.returncode != 0 and not run.reports
    assert "the loop does not separate the mesh" in run.log, run.log[-2000:]


# ---- stitching ----------------------------------------------------------------

def two_sheets(nA=7, nB=11, gap=0.2):
    A = sheet(nA, 0.0, 1.0)
    B = sheet(nB, 1.0 + gap, 2.0 + gap, z=lambda x, y: 0.1 * (x - 1.0 - gap) * y)  # not coplanar
    right_of_a = [(nA - 1) * nA + j for j in range(nA)]
    left_of_b = [j for j in range(nB)]
    return A, B, right_of_a, left_of_b


def outline(nA, nB):
    return 3 * (nA - 1) + 3 * (nB - 1) + 2  # both sheets' other sides and the two end rungs


def test_stitch_two_open_sheets_across_a_gap(tmp_path):
    nA, nB = 7, 11
    A, B, pa, pb = two_sheets(nA, nB)
    V, F = joined(A, B)
    path = write_off(tmp_path / "sheets.off", V, F)
    out = tmp_path / "stitched.ply"
    script = mlx((STITCH, {"path_a": indices(pa), "path_b": indices(p + len(A[0]) for p in pb),
                           "report_file": "{report0}"}))
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert r["faces_added"] == (nA - 1) + (nB - 1)
    assert r["border_edges_before"] == 4 * (nA - 1) + 4 * (nB - 1)
    assert r["border_edges_after"] == after["border_edges"] == outline(nA, nB)
    assert after["connected_components"] == 1 and after["border_loops"] == 1
    assert after["vertices"] == len(V)  # no new vertex
    assert r["new_intersecting_pairs"] == 0
    expect_clean(after)
    for key in REPORT_KEYS:
        assert key in r


def test_stitch_two_paths_from_the_selection(tmp_path):
    nA, nB = 6, 9
    A, B, _, _ = two_sheets(nA, nB)
    path = write_off(tmp_path / "sheets.off", *joined(A, B))
    out = tmp_path / "stitched.ply"
    script = before(mlx((STITCH, {"report_file": "{report0}"})), STITCH,
                    [condition("Vertex", "(x > 0.99) && (x < 1.21)")])
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    after = meshcheck(out)
    assert after["border_edges"] == outline(nA, nB) and after["connected_components"] == 1
    expect_clean(after)
    # Three runs selected: the message lists them.
    script = before(mlx((STITCH, {"report_file": "{report0}"})), STITCH,
                    [condition("Vertex", "((x > 0.99) && (x < 1.21)) || (x < 0.01)")])
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode != 0 and "form 3 paths along border edges" in run.log, run.log[-2000:]


@pytest.mark.parametrize("output", [0, 1])
def test_stitch_one_path_on_each_of_two_layers(tmp_path, output):
    nA, nB = 7, 11
    A, B, pa, pb = two_sheets(nA, nB)
    a = write_off(tmp_path / "a.off", *A)
    b = write_off(tmp_path / "b.off", *B)
    out = tmp_path / "stitched.ply"
    script = mlx((STITCH, {"paths_from": 1, "first_layer": 0, "second_layer": 1,
                           "path_a": indices(pa), "path_b": indices(pb), "output": output,
                           "select_new_faces": True, "report_file": "{report0}"}))
    run = run_server(tmp_path, [a, b], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert r["output"] == ("new layer" if output == 0 else "first layer")
    assert after["faces"] == len(A[1]) + len(B[1]) + r["faces_added"]
    assert after["border_edges"] == outline(nA, nB) and after["connected_components"] == 1
    expect_clean(after)
    assert ("second layer was merged into it" in run.log) == (output == 1)


def test_stitch_wide_gap_with_subdivision(tmp_path):
    nA, nB = 7, 11
    A, B, pa, pb = two_sheets(nA, nB, gap=0.8)
    V, F = joined(A, B)
    path = write_off(tmp_path / "sheets.off", V, F)
    out = tmp_path / "stitched.ply"
    script = mlx((STITCH, {"path_a": indices(pa), "path_b": indices(p + len(A[0]) for p in pb),
                           "max_aspect_ratio": 2, "report_file": "{report0}"}))
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert r["vertices_added"] > 0 and after["vertices"] == len(V) + r["vertices_added"]
    assert after["connected_components"] == 1 and after["border_loops"] == 1
    assert "stored in float" in run.log
    expect_clean(after)  # the float-rounded new vertices too


def test_stitch_sequence_covers_a_junction(tmp_path):
    """Figure 3: three patches around a junction; the first stitch's leftover
    paths are concatenated so the second stitch covers the junction."""
    n = 6
    patches, minus, plus = [], [], []
    offset = 0
    for k in range(3):
        u = (math.cos(2 * math.pi * k / 3), math.sin(2 * math.pi * k / 3))
        v = (math.cos(2 * math.pi * (k + 1) / 3), math.sin(2 * math.pi * (k + 1) / 3))
        c = ((u[0] + v[0]) / 2, (u[1] + v[1]) / 2)
        Vk = []
        for i in range(n + 1):
            for j in range(n + 1):
                p = (u[0] * i / n + v[0] * j / n, u[1] * i / n + v[1] * j / n)
                Vk.append((c[0] + (p[0] - c[0]) * 0.94, c[1] + (p[1] - c[1]) * 0.94, 0.0))
        Fk = []
        for i in range(n):
            for j in range(n):
                a, b, cc, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, \
                    i * (n + 1) + j + 1
                Fk += [(a, b, cc), (a, cc, d)]
        minus.append([offset + i * (n + 1) for i in range(n + 1)])  # j = 0, from the inner corner
        plus.append([offset + j for j in range(n + 1)])  # i = 0
        patches.append((Vk, Fk))
        offset += len(Vk)
    V, F = joined(*patches)
    path = write_off(tmp_path / "three.off", V, F)
    third = plus[2][::-1] + minus[2][1:]
    paths = "; ".join(indices(p) for p in (plus[0], minus[1], minus[0], plus[1], third))
    out = tmp_path / "out.ply"
    script = mlx((STITCH, {"paths_from": 2, "paths": paths, "stitch_pairs": "0 1; 2 4",
                           "report_file": "{report0}"}))
    run = run_server(tmp_path, [path], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out)
    assert len(r["steps"]) == 2 and "concatenated at the junction" in run.log
    assert r["new_intersecting_pairs"] == 0
    assert after["connected_components"] == 1 and after["border_loops"] == 1
    assert after["border_edges"] == r["border_edges_after"] == 3 * 2 * n + 3
    expect_clean(after)


def test_stitch_bad_input(tmp_path):
    A, B, pa, pb = two_sheets()
    path = write_off(tmp_path / "sheets.off", *joined(A, B))
    interior = (len(A[0]) // 2)
    for values, message in [
        ({"path_a": indices(pa), "path_b": f"{interior} {interior + 1}"}, "not on a border"),
        ({"path_a": indices(pa), "path_b": ""}, "give both path_a and path_b"),
        ({"path_a": "1 x 2", "path_b": "3 4"}, "'x' is not a vertex index"),
        ({"path_a": indices(pa), "path_b": "100000 100001"}, "names vertex 100000"),
    ]:
        run = run_server(tmp_path, [path], mlx((STITCH, {**values, "report_file": "{report0}"})))
        assert run.returncode != 0 and message in run.log and not run.reports, (message,
                                                                               run.log[-2000:])


# ---- closing gaps: the corpus against CGAL's stitch_borders ----------------------

def stl_soup(path):
    """An STL's facets as a soup (three vertices each, none shared), in the
    order the file lists them: what peer_stitch starts from."""
    data = path.read_bytes()
    V, F = [], []
    if data[:5].lower() == b"solid" and b"facet" in data[:1000]:
        for line in data.decode("ascii", "replace").splitlines():
            parts = line.split()
            if parts and parts[0] == "vertex":
                V.append(tuple(float(x) for x in parts[1:4]))
    else:
        (count,) = struct.unpack_from("<I", data, 80)
        for k in range(count):
            values = struct.unpack_from("<12f", data, 84 + 50 * k)
            V += [values[3:6], values[6:9], values[9:12]]
    F = [(3 * k, 3 * k + 1, 3 * k + 2) for k in range(len(V) // 3)]
    return V, F


def corpus():
    if not (DATA / "stitching").is_dir():
        return ["stitching"]  # the test skips with the reason
    return sorted(p.name for p in (DATA / "stitching").iterdir())


def peer_stitch(path):
    if not PEER_STITCH.is_file():
        pytest.fail(f"{PEER_STITCH} is missing: scripts/test builds it from ../shared/tools")
    out = subprocess.run([str(PEER_STITCH), str(path)], capture_output=True, text=True)
    return json.loads(out.stdout)


def read_off(path):
    tokens = path.read_text().split()
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    V = [tuple(float(x) for x in tokens[4 + 3 * k:7 + 3 * k]) for k in range(nv)]
    F, pos = [], 4 + 3 * nv
    for _ in range(nf):
        k = int(tokens[pos])
        F.append(tuple(int(x) for x in tokens[pos + 1:pos + 1 + k]))
        pos += 1 + k
    return V, F


def welded(V, F):
    """Vertices with equal coordinates made one (the faces keep their corners)."""
    index, W = {}, []
    for v in V:
        index.setdefault(tuple(v), len(index))
    W = [None] * len(index)
    for v, i in index.items():
        W[i] = v
    return W, [tuple(index[tuple(V[c])] for c in f) for f in F]


def border_edge_count(F):
    """Edges used by exactly one face (faces with a repeated corner ignored)."""
    uses = {}
    for f in F:
        if len(set(f)) < len(f):
            continue
        for u, v in zip(f, f[1:] + f[:1]):
            uses[frozenset((u, v))] = uses.get(frozenset((u, v)), 0) + 1
    return sum(1 for n in uses.values() if n == 1)


@pytest.mark.parametrize("name", corpus())
def test_close_gaps_leaves_fewer_borders_than_cgal(tmp_path, name):
    """Where CGAL's stitch_borders leaves more border edges than merging
    every pair of equal points would (the file welded, faces with a
    repeated corner left out), ours leaves fewer, and never more than that
    welded count; edge-manifold, consistently oriented, and no face pair
    intersecting that does not in the welded file."""
    require_shared_data()
    source = DATA / "stitching" / name
    # STL: the facet soup as an OFF, so that both start from the same
    # unwelded soup (MeshLab's STL importer would weld it first).
    src = write_off(tmp_path / (source.stem + "_soup.off"), *stl_soup(source)) \
        if source.suffix.lower() == ".stl" else source
    cgal = peer_stitch(src)
    V, F = read_off(src)
    WV, WF = welded(V, F)
    reachable = border_edge_count(WF)
    welded_file = write_off(tmp_path / "welded.off", WV, WF)
    out = tmp_path / "closed.ply"
    run = run_server(tmp_path, [src], sample("close_gaps.mlx"), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    changed = r["vertices_merged"] or r["faces_added"] or r["faces_flipped"]
    if not changed:
        out = src  # nothing changed: the layer is left as it was
    after = meshcheck(out)
    OV, OF, _ = read_ply(out) if changed else (V, F, None)
    ours_welded = write_off(tmp_path / "ours_welded.off", *welded(np.array(OV).tolist(),
                                                                  np.array(OF).tolist()))
    pairs_welded_input = meshcheck(welded_file)["self_intersecting_pairs"]
    pairs_welded_ours = meshcheck(ours_welded)["self_intersecting_pairs"]
    print(f"\n{name}: border edges before {r['border_edges_before']}, ours {after['border_edges']}"
          f" (merged {r['vertices_merged']} vertices, flipped {r['faces_flipped']} faces, removed "
          f"{r['degenerate_faces_removed']} collapsed faces, {r['faces_added']} faces added), "
          f"CGAL stitch_borders {cgal['border_edges_after']}, welded file {reachable}; "
          f"non-manifold edges ours {after['non_manifold_edges']}, orientation-inconsistent ours "
          f"{after['orientation_inconsistent_edges']}; intersecting pairs welded: input "
          f"{pairs_welded_input}, ours {pairs_welded_ours}")
    assert r["border_edges_after"] == after["border_edges"]
    assert after["border_edges"] <= min(reachable, cgal["border_edges_after"])
    if cgal["border_edges_after"] > reachable:
        assert after["border_edges"] < cgal["border_edges_after"]
    assert after["non_manifold_edges"] == 0
    assert after["orientation_inconsistent_edges"] == 0
    assert pairs_welded_ours <= pairs_welded_input
    for key in REPORT_KEYS:
        assert key in r


def test_close_gaps_closes_slits_one_edge_wide_by_default(tmp_path):
    """CGAL's pinched grid: after the merge, its inside borders are slits
    one grid cell (0.1, 8.6 % of the diagonal) wide, beyond the default
    max_gap (1 %) but as narrow as their border edges, so the default local
    bound closes them and only the grid's outline (32 edges) stays open
    (the rest of an L-shaped slit, if a first stitch leaves it, in a second
    round). With the diagonal's fraction alone
    they stay open, unless max_gap reaches their width."""
    require_shared_data()
    src = DATA / "stitching" / "cgaltest_pinched.off"
    runs = {}
    for name, max_gap, factor in (("default", "0.01", "1.5"), ("global", "0.01", "0"),
                                  ("wide", "0.1", "0")):
        out = tmp_path / f"closed_{name}.ply"
        script = sample("close_gaps.mlx").replace(
            'name="max_gap" value="0.01"', f'name="max_gap" value="{max_gap}"').replace(
            'name="local_gap_factor" value="1.5"', f'name="local_gap_factor" value="{factor}"')
        run = run_server(tmp_path, [src], script, outputs=[out])
        assert run.returncode == 0, run.log[-3000:]
        after = meshcheck(out)
        assert run.report["border_edges_after"] == after["border_edges"]
        expect_clean(after)
        runs[name] = run.report
    print("\npinched: border edges " + ", ".join(
        f"{name} {r['border_edges_after']} ({r['gaps_stitched']} of {r['gaps_found']} facing "
        f"pairs stitched)" for name, r in runs.items()))
    assert runs["default"]["border_edges_after"] == 32 and runs["default"]["faces_added"] == 18
    assert runs["global"]["border_edges_after"] == 56 and runs["global"]["faces_added"] == 0
    assert runs["wide"]["border_edges_after"] == 32 and runs["wide"]["faces_added"] == 18


# ---- an assembly of two real range scans --------------------------------------


def test_two_range_scans_trimmed_and_stitched_into_one_part(tmp_path):
    """lato000 and lato180 (opposite sides of one object, aligned by
    partial.mlp, their borders about 50 units apart across the unscanned
    flank): each scan's ragged border facing the other is trimmed away along
    a cut through the inside, and the two cuts are stitched, with
    subdivision, into one part (range_scan_assembly.py): no hole between the
    cuts, edge-manifold, consistently oriented, no intersecting pair."""
    require_shared_data()
    result = assemble(tmp_path)
    run, cuts, offset = result.run, result.cuts, result.offset
    assert run.returncode == 0, run.log[-3000:]
    trim_a, trim_b_report, stitched = run.reports
    after = meshcheck(result.output)
    V, F, _ = read_ply(result.output)
    _, Fmain = main_component(V, F)
    # No hole between the cuts: every cut edge has a face on each side (the
    # kept faces' vertices keep their indices; the second layer follows the first).
    uses = {}
    for a, b, c in F.tolist():
        for u, v in ((a, b), (b, c), (c, a)):
            uses[frozenset((u, v))] = uses.get(frozenset((u, v)), 0) + 1
    cut_edges = [frozenset((u, v)) for u, v in zip(cuts[0], cuts[0][1:])]
    cut_edges += [frozenset((u + offset, v + offset)) for u, v in zip(cuts[1], cuts[1][1:])]
    print(f"\nrange scans: cuts {len(cuts[0])} / {len(cuts[1])} vertices; trimmed "
          f"{trim_a['faces_removed']} + {trim_b_report['faces_removed']} faces; stitched "
          f"{stitched['faces_added']} faces, {stitched['vertices_added']} new vertices, in "
          f"{stitched['time_ms']:.0f} ms; border edges {stitched['border_edges_before']} -> "
          f"{stitched['border_edges_after']}; intersecting pairs {after['self_intersecting_pairs']}")
    assert trim_a["faces_removed"] > 0 and trim_b_report["faces_removed"] > 0
    assert len(Fmain) == len(F)  # one vertex-connected part
    assert all(uses.get(e) == 2 for e in cut_edges)
    assert stitched["border_edges_after"] == after["border_edges"]
    assert after["non_manifold_edges"] == 0 and after["orientation_inconsistent_edges"] == 0
    assert after["self_intersecting_pairs"] == 0
    assert stitched["new_intersecting_pairs"] == 0
