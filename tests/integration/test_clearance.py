"""Measure Clearance and Enforce Minimum Clearance through meshlabserver:
nested spheres and parallel sheets generated here, the aligned range scans
of the corpus (layer matrices from a MeshLab project), bad input. Results are
checked by meshcheck --min-distance where one file holds every pair in scope,
and between layers by an independent numpy triangle-triangle distance."""
import math
import re
import subprocess

import numpy as np
import pytest

from conftest import (DATA, ROOT, meshcheck, mlx, read_ply, require_shared_data, run_server,
                      write_off, write_ply)

MEASURE = "MeshMend: Measure Clearance"
ENFORCE = "MeshMend: Enforce Minimum Clearance"


def rounding_tolerance(diagonal):
    """What float storage can take off a distance: each coordinate is rounded
    by at most 2^-24 of its magnitude (< the diagonal here), so two points by
    at most 2 * sqrt(3) * 2^-24 * diagonal. The filter aims beyond tau by more
    than that and checks the rounded result; this only keeps the test honest
    about what it relies on."""
    return 2 * math.sqrt(3) * 2.0 ** -24 * diagonal


# ---- meshes ------------------------------------------------------------------

def icosphere(level, radius=1.0, center=(0, 0, 0), inward=False):
    t = (1 + 5 ** 0.5) / 2
    V = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    V = [np.array(v, float) / np.linalg.norm(v) for v in V]
    F = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        mid, G = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = V[a] + V[b]
                V.append(p / np.linalg.norm(p))
                mid[key] = len(V) - 1
            return mid[key]

        for a, b, c in F:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            G += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        F = G
    V = [tuple(radius * v + np.array(center, float)) for v in V]
    if inward:
        F = [(a, c, b) for a, b, c in F]
    return V, F


def combined(*parts):
    V, F = [], []
    for pv, pf in parts:
        F += [tuple(i + len(V) for i in f) for f in pf]
        V += list(pv)
    return V, F


def sheet(n, size, z, shift=(0.0, 0.0)):
    """An n x n grid of squares (two triangles each) in the plane z."""
    V = [(shift[0] + size * i / n, shift[1] + size * j / n, z) for j in range(n + 1)
         for i in range(n + 1)]
    F = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            F += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    return V, F


def nested_spheres():
    """A shell: the outer skin (radius 1) and an inner skin (radius 0.9,
    facing inward) pushed off centre, so that the gap is 0.03 on one side."""
    return combined(icosphere(3), icosphere(3, 0.9, (0.07, 0, 0), inward=True))


# ---- an independent distance between two triangle sets ------------------------

def _point_segment(p, a, b):
    ab = b - a
    l2 = np.einsum("ij,ij->i", ab, ab)
    s = np.where(l2 > 0, np.einsum("ij,ij->i", p - a, ab) / np.where(l2 > 0, l2, 1), 0)
    s = np.clip(s, 0, 1)
    return np.linalg.norm(p - (a + s[:, None] * ab), axis=1)


def _point_triangle(p, a, b, c):
    """Foot of the perpendicular inside the triangle: the plane distance;
    otherwise the nearest edge."""
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    h = np.einsum("ij,ij->i", p - a, n) / np.where(nn > 0, nn, 1)
    q = p - h[:, None] * n
    inside = nn > 0
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, q - u), n) >= 0
    edges = np.minimum(np.minimum(_point_segment(p, a, b), _point_segment(p, b, c)),
                       _point_segment(p, c, a))
    return np.where(inside, np.abs(h) * np.sqrt(nn), edges)


def _segment_segment(p0, p1, q0, q1):
    """The lines' closest points when inside both segments, else an end point
    against the other segment."""
    u, v, w = p1 - p0, q1 - q0, p0 - q0
    a, b, c = (np.einsum("ij,ij->i", x, y) for x, y in ((u, u), (u, v), (v, v)))
    d, e = np.einsum("ij,ij->i", u, w), np.einsum("ij,ij->i", v, w)
    den = a * c - b * b
    ok = den > 1e-18 * a * c
    safe = np.where(ok, den, 1)
    s, t = (b * e - c * d) / safe, (a * e - b * d) / safe
    ok &= (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    interior = np.linalg.norm(w + s[:, None] * u - t[:, None] * v, axis=1)
    ends = np.minimum.reduce([_point_segment(p0, q0, q1), _point_segment(p1, q0, q1),
                              _point_segment(q0, p0, p1), _point_segment(q1, p0, p1)])
    return np.where(ok, np.minimum(interior, ends), ends)


def min_distance_between(VA, FA, VB, FB, limit):
    """The smallest distance between a triangle of A and one of B (disjoint
    triangles: the smallest vertex-face or edge-edge distance), over the
    pairs closer than `limit`; inf when there is none. Candidates: pairs
    whose boxes, grown by limit/2, share a grid cell of size limit."""
    h = float(limit)

    def cells(V, F):
        T = V[F]
        lo = np.floor((T.min(1) - h / 2) / h).astype(np.int64)
        hi = np.floor((T.max(1) + h / 2) / h).astype(np.int64)
        span = hi - lo + 1
        faces, keys = [], []
        for dx in range(span[:, 0].max()):
            for dy in range(span[:, 1].max()):
                for dz in range(span[:, 2].max()):
                    m = (dx < span[:, 0]) & (dy < span[:, 1]) & (dz < span[:, 2])
                    c = lo[m] + np.array([dx, dy, dz])
                    keys.append((c[:, 0] * 2000003 + c[:, 1]) * 2000003 + c[:, 2])
                    faces.append(np.nonzero(m)[0])
        return np.concatenate(keys), np.concatenate(faces)

    ka, fa = cells(VA, FA)
    kb, fb = cells(VB, FB)
    order = np.argsort(kb, kind="stable")
    kb, fb = kb[order], fb[order]
    first, last = np.searchsorted(kb, ka, "left"), np.searchsorted(kb, ka, "right")
    count = last - first
    if count.sum() == 0:
        return math.inf
    ia = np.repeat(fa, count)
    starts = np.repeat(first - np.concatenate([[0], np.cumsum(count)[:-1]]), count)
    ib = fb[np.arange(count.sum()) + starts]
    pairs = np.unique(ia * len(FB) + ib)
    ia, ib = pairs // len(FB), pairs % len(FB)
    A, B = VA[FA[ia]], VB[FB[ib]]
    best = math.inf
    for k in range(3):
        best = min(best, _point_triangle(A[:, k], B[:, 0], B[:, 1], B[:, 2]).min(),
                   _point_triangle(B[:, k], A[:, 0], A[:, 1], A[:, 2]).min())
        for j in range(3):
            best = min(best, _segment_segment(A[:, k], A[:, (k + 1) % 3], B[:, j],
                                              B[:, (j + 1) % 3]).min())
    return best if best < limit else math.inf


def test_the_independent_distance_agrees_with_meshcheck(tmp_path):
    """Two coarse spheres in one file: meshcheck's smallest distance is the
    one between them (their own faces are farther apart)."""
    rng = np.random.default_rng(7)
    A = icosphere(1)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    B = icosphere(1, 1.0, (2.3, 0.4, 0.2))
    VB = [tuple(q @ (np.array(v) - (2.3, 0.4, 0.2)) + (2.3, 0.4, 0.2)) for v in B[0]]
    path = write_off(tmp_path / "two.off", *combined(A, (VB, B[1])))
    check = meshcheck(path, "--min-distance")["min_distance"]
    assert (check["face_a"] < 80) != (check["face_b"] < 80), check  # one face of each
    ours = min_distance_between(np.array(A[0]), np.array(A[1]), np.array(VB), np.array(B[1]), 1.0)
    assert ours == pytest.approx(check["distance"], rel=1e-9)


# ---- enforcing within one layer ----------------------------------------------

def enforce_script(**values):
    return mlx((ENFORCE, {"report_file": "{report0}", **values}))


def test_nested_spheres_pushed_to_tau(tmp_path):
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    before = meshcheck(src, "--min-distance")
    assert before["self_intersecting_pairs"] == 0
    assert before["min_distance"]["distance"] == pytest.approx(0.03, abs=2e-3)
    tau = 0.06
    out = tmp_path / "shell_out.ply"
    run = run_server(tmp_path, [src], enforce_script(tau=tau), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    after = meshcheck(out, "--min-distance")
    tolerance = rounding_tolerance(after["bbox_diagonal"])
    assert r["reached"] and r["stop_reason"] == "reached", r
    assert after["min_distance"]["distance"] >= tau - tolerance, (after["min_distance"], r)
    assert r["min_distance_after"] >= tau
    assert after["self_intersecting_pairs"] == 0
    assert (after["vertices"], after["faces"]) == (len(V), len(F))
    assert r["min_distance_before"] == pytest.approx(before["min_distance"]["distance"], rel=1e-6)
    assert r["violating_pairs_before"] > 0 and r["violating_pairs_after"] == 0
    # Displacements: at least what the worst pair needs ((tau - d) / 2 on
    # each side), and of that order, not a reshaping of the shell.
    need = (tau - r["min_distance_before"]) / 2
    assert r["displacement_lower_bound"] == pytest.approx(need, rel=1e-6)
    assert need * (1 - 1e-6) <= r["max_displacement"] <= 3 * need, r
    assert 0 < r["mean_displacement"] <= r["max_displacement"]
    # Only the vertices the report counts moved; the others are bit-identical.
    Vout, Fout, _ = read_ply(out)
    Vin = np.array(V, np.float32).astype(float)
    moved = np.linalg.norm(Vout - Vin, axis=1)
    assert np.count_nonzero(moved) == r["vertices_moved"] > 0
    assert moved.max() <= r["max_displacement"] * (1 + 1e-6) + tolerance
    assert np.array_equal(Fout, np.array(F))
    for key in ("tau", "min_distance_before", "min_distance_after", "violating_pairs_before",
                "violating_pairs_after", "max_displacement", "mean_displacement", "time_ms"):
        assert key in r
    assert "reached" in run.log and "vertices moved" in run.log


def test_the_cap_stops_short_and_reports_the_pairs(tmp_path):
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    out = tmp_path / "capped.ply"
    run = run_server(tmp_path, [src], enforce_script(tau=0.06, max_displacement=0.005),
                     outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    assert not r["reached"] and r["violating_pairs_after"] > 0 and r["short_pairs"]
    # The cap holds up to the float rounding of the final positions.
    assert r["max_displacement"] <= 0.005 + rounding_tolerance(2.0)
    assert r["min_distance_after"] > r["min_distance_before"]
    assert "tau not reached" in run.log
    after = meshcheck(out, "--min-distance")
    assert after["self_intersecting_pairs"] == 0
    assert after["min_distance"]["distance"] == pytest.approx(r["min_distance_after"], rel=1e-6)


# ---- measuring ---------------------------------------------------------------

def coarse_sheets(d):
    """Two 2 x 2 sheets d apart, overlapping over [1, 2] x [0.25, 2]. Their
    cells are 0.5 wide: non-adjacent faces of one sheet are at least
    0.5 / sqrt(2) = 0.354 apart, farther than 2 tau in these tests."""
    return combined(sheet(4, 2.0, 0.0), sheet(4, 2.0, d, shift=(1.0, 0.25)))


def test_measure_parallel_sheets_at_a_known_distance(tmp_path):
    d, tau = 0.1, 0.15
    V, F = coarse_sheets(d)
    src = write_ply(tmp_path / "sheets.ply", V, F)
    out = tmp_path / "measured.ply"
    script = mlx((MEASURE, {"tau": tau, "report_file": "{report0}"}))
    cmd = [str(ROOT / "scripts" / "meshlabserver"), "-i", str(src), "-o", str(out), "-m", "vq",
           "-s", str(tmp_path / "script.mlx")]
    (tmp_path / "script.mlx").write_text(script.replace("{report0}", str(tmp_path / "m.json")))
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log[-3000:]
    import json
    r = json.loads((tmp_path / "m.json").read_text())
    assert r["min_distance"] == pytest.approx(d, abs=1e-6)
    assert r["min_distance"] == pytest.approx(meshcheck(src, "--min-distance")["min_distance"]
                                              ["distance"], rel=1e-6)
    assert r["tau"] == pytest.approx(tau)
    # The faces over the overlap are closer than tau; the histogram counts
    # the pairs below 2 tau.
    assert r["faces_below_tau"] > 0 and r["violating_pairs"] > 0
    assert sum(r["histogram"]) >= r["violating_pairs"]
    assert r["closest"]["distance"] == pytest.approx(d, abs=1e-6)
    assert "minimum 0.1 " in log and "face pairs by distance" in log
    # Quality = local clearance: d over the overlap, the cap 2 tau elsewhere.
    Vout, _, values = read_ply(out)
    q = values["quality"]
    assert q.min() == pytest.approx(d, abs=1e-6) and q.max() == pytest.approx(2 * tau, rel=1e-6)
    np.testing.assert_array_equal(Vout, np.array(V, np.float32).astype(float))  # nothing moved


def test_measure_sample_gives_the_minimum_of_the_shell(tmp_path):
    """samples/measure_clearance.mlx (tau 0: only the minimum) agrees with
    meshcheck on the nested spheres."""
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    script = (ROOT / "samples" / "measure_clearance.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"')
    run = run_server(tmp_path, [src], script)
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    check = meshcheck(src, "--min-distance")["min_distance"]
    assert r["min_distance"] == pytest.approx(check["distance"], rel=1e-6)
    # One face of each skin (the outer one holds the first 1280 faces); the
    # icosphere's symmetry makes several pairs tie, so not necessarily meshcheck's.
    assert (r["closest"]["face_a"] < 1280) != (r["closest"]["face_b"] < 1280)
    assert r["violating_pairs"] == 0 and r["faces_below_tau"] == 0
    assert r["local_max"] == pytest.approx(2 * r["min_distance"])


def test_measure_and_select_then_delete_the_close_faces(tmp_path):
    d, tau = 0.1, 0.15
    V, F = coarse_sheets(d)
    src = write_ply(tmp_path / "sheets.ply", V, F)
    out = tmp_path / "far.ply"
    script = mlx((MEASURE, {"tau": tau, "report_file": "{report0}"})).replace(
        "</FilterScript>", ' <filter name="Delete Selected Faces"/>\n</FilterScript>')
    run = run_server(tmp_path, [src], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    after = meshcheck(out, "--min-distance")
    assert after["faces"] == len(F) - r["faces_below_tau"]
    # What is left is at least tau apart.
    assert after["min_distance"]["distance"] >= tau - 1e-6


# ---- two layers, placed by their matrices ---------------------------------------

def project(path, layers):
    """A MeshLab project with (file, 4x4 matrix) layers, in loading order."""
    lines = ["<!DOCTYPE MeshLabDocument>", "<MeshLabProject>", " <MeshGroup>"]
    for f, m in layers:
        lines.append(f'  <MLMesh label="{f.name}" filename="{f}">')
        lines.append("   <MLMatrix44>\n" + "".join(" ".join(repr(float(x)) for x in row) + " \n"
                                               for row in m) + "</MLMatrix44>")
        lines.append("  </MLMesh>")
    lines += [" </MeshGroup>", " <RasterGroup/>", "</MeshLabProject>"]
    path.write_text("\n".join(lines) + "\n")
    return path


def run_project(tmp_path, mlp, script_text, outputs):
    report = tmp_path / "report.json"
    if report.exists():
        report.unlink()
    script = tmp_path / "script.mlx"
    script.write_text(script_text.replace("{report0}", str(report)))
    cmd = [str(ROOT / "scripts" / "meshlabserver"), "-p", str(mlp)]
    for i, o in enumerate(outputs):
        cmd += ["-o", str(o), "-l", str(i)]
    cmd += ["-s", str(script)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    import json
    return proc.returncode, proc.stdout + proc.stderr, (json.loads(report.read_text())
                                                         if report.exists() else None)


def placed(path, matrix):
    """The stored vertices placed by the matrix as MeshLab holds it: in float
    (partial.mlp's -1293.21 is -1293.2099609375 there, which moves the
    distance between the scans by 8e-5)."""
    V, F, _ = read_ply(path)
    M = np.array(matrix, np.float32).astype(float)
    return V @ M[:3, :3].T + M[:3, 3], F


def rotation(angle_deg, axis):
    a = math.radians(angle_deg)
    x, y, z = np.array(axis, float) / np.linalg.norm(axis)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                     [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])


def test_between_layers_in_their_own_frames(tmp_path):
    """Sheet B is stored at the origin and placed 0.2 above sheet A by a
    rotation and a translation: the filters see it where the matrix puts it,
    and the moved vertices are written back in B's own frame."""
    d, tau = 0.2, 0.35
    a = write_ply(tmp_path / "a.ply", *sheet(10, 2.0, 0.0))
    R = rotation(30, (0, 0, 1))
    VB, FB = sheet(10, 2.0, 0.0, shift=(-1.0, -1.0))
    # B's file holds the sheet in B's frame: R^-1 (placed - t).
    t = np.array([1.0, 1.0, d])
    b = write_ply(tmp_path / "b.ply", [tuple(R.T @ np.array(v)) for v in VB], FB)
    MB = np.eye(4)
    MB[:3, :3], MB[:3, 3] = R, t
    mlp = project(tmp_path / "pair.mlp", [(a, np.eye(4)), (b, MB)])

    outs = [tmp_path / "a_out.ply", tmp_path / "b_out.ply"]
    code, log, r = run_project(tmp_path, mlp, mlx((MEASURE, {
        "tau": tau, "scope": 1, "first_layer": 0, "second_layer": 1,
        "report_file": "{report0}"})), outs)
    assert code == 0, log[-3000:]
    assert r["min_distance"] == pytest.approx(d, abs=1e-5), r

    code, log, r = run_project(tmp_path, mlp, enforce_script(
        tau=tau, scope=1, first_layer=0, second_layer=1), outs)
    assert code == 0, log[-3000:]
    assert r["reached"] and r["min_distance_before"] == pytest.approx(d, abs=1e-5)
    A, FA = placed(outs[0], np.eye(4))
    B, FB2 = placed(outs[1], MB)
    found = min_distance_between(A, FA, B, FB2, 2 * tau)
    assert found >= tau - rounding_tolerance(4.0), (found, r)
    assert found == pytest.approx(r["min_distance_after"], rel=1e-6)
    # Both sides moved (half the shortfall each), each in its own frame.
    VAin = np.array(sheet(10, 2.0, 0.0)[0], np.float32).astype(float)
    assert np.abs(A - VAin).max() > 0.5 * (tau - d) * 0.99
    Bin = read_ply(b)[0]
    Bout = read_ply(outs[1])[0]
    assert np.abs(Bout[:, 2] - Bin[:, 2]).max() > 0.5 * (tau - d) * 0.99
    # Moved along its own z only (x and y up to float rounding).
    np.testing.assert_allclose(Bout[:, :2], Bin[:, :2], rtol=0, atol=4 * rounding_tolerance(4.0))


# ---- bad input -------------------------------------------------------------------

def test_bad_input(tmp_path):
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    for tau in (0, -0.1):
        run = run_server(tmp_path, [src], enforce_script(tau=tau))
        assert run.returncode != 0 and "tau must be more than 0" in run.log, run.log[-2000:]
        assert "Problem with filter" in run.log
        assert not run.reports
    run = run_server(tmp_path, [src], mlx((MEASURE, {"tau": -1, "report_file": "{report0}"})))
    assert run.returncode != 0 and "tau must be a distance of 0 or more" in run.log
    run = run_server(tmp_path, [src], enforce_script(tau=0.06, max_iterations=0))
    assert run.returncode != 0 and "max iterations" in run.log
    run = run_server(tmp_path, [src], enforce_script(tau=0.06, scope=1, first_layer=0,
                                                     second_layer=0))
    assert run.returncode != 0 and "chosen twice" in run.log


def test_intersecting_input_names_the_filter_to_run_first(tmp_path):
    # Within a layer: a sphere poking through the other.
    V, F = combined(icosphere(2), icosphere(2, 0.5, (0.8, 0, 0)))
    src = write_ply(tmp_path / "crossing.ply", V, F)
    out = tmp_path / "out.ply"
    run = run_server(tmp_path, [src], enforce_script(tau=0.05), outputs=[out])
    assert run.returncode != 0 and not run.reports
    assert "intersects itself" in run.log and "MeshMend: Remove Self-Intersections" in run.log
    assert "crossing.ply" in run.log  # the layer by name
    # Between layers.
    a = write_ply(tmp_path / "a.ply", *icosphere(2))
    b = write_ply(tmp_path / "b.ply", *icosphere(2, 0.5, (0.8, 0, 0)))
    run = run_server(tmp_path, [a, b], enforce_script(tau=0.05, scope=1, first_layer=0,
                                                      second_layer=1))
    assert run.returncode != 0 and not run.reports
    assert "MeshMend: Intersect and Split Layers" in run.log, run.log[-2000:]


def test_everything_locked_is_reported_and_nothing_moves(tmp_path):
    """Locked vertices that make tau unreachable are an outcome, not an
    error: the filter succeeds, says why tau was not reached, and the mesh
    stays as it was."""
    V, F = nested_spheres()
    src = write_ply(tmp_path / "shell.ply", V, F)
    out = tmp_path / "locked.ply"
    script = enforce_script(tau=0.06, lock_selected=True).replace(
        "<FilterScript>", '<FilterScript>\n <filter name="Select All">\n'
        '  <Param type="RichBool" name="allFaces" value="true"/>\n'
        '  <Param type="RichBool" name="allVerts" value="true"/>\n </filter>')
    run = run_server(tmp_path, [src], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    assert not r["reached"] and r["stop_reason"] == "locked", r
    assert r["locked_vertices"] == len(V) and r["vertices_moved"] == 0
    assert r["violating_pairs_after"] == r["violating_pairs_before"] > 0
    assert r["displacement_lower_bound"] == pytest.approx(0.06 - r["min_distance_before"])
    assert "tau not reached" in run.log and "only locked" in run.log
    Vout, _, _ = read_ply(out)
    np.testing.assert_array_equal(Vout, np.array(V, np.float32).astype(float))


def test_locking_one_skin_moves_only_the_other(tmp_path):
    V, F = nested_spheres()
    outer = len(icosphere(3)[0])
    src = write_ply(tmp_path / "shell.ply", V, F)
    out = tmp_path / "one_side.ply"
    # Select the outer skin (radius 1; the inner one reaches 0.97).
    select = (' <filter name="Conditional Vertex Selection">\n'
              '  <Param type="RichString" name="condSelect" value="(x*x+y*y+z*z) &gt; 0.99"/>\n'
              " </filter>\n")
    script = enforce_script(tau=0.06, lock_selected=True).replace(
        "<FilterScript>\n", "<FilterScript>\n" + select)
    run = run_server(tmp_path, [src], script, outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r = run.report
    assert r["reached"] and r["locked_vertices"] == outer, r
    Vout, _, _ = read_ply(out)
    Vin = np.array(V, np.float32).astype(float)
    assert np.array_equal(Vout[:outer], Vin[:outer])
    # The free side moves the whole shortfall.
    assert r["max_displacement"] >= (0.06 - r["min_distance_before"]) * (1 - 1e-6)
    assert meshcheck(out, "--min-distance")["min_distance"]["distance"] >= 0.06 - 1e-6


# ---- the aligned range scans (corpus) ----------------------------------------------

def scan_matrices():
    text = (DATA / "range_scans" / "partial.mlp").read_text()
    found = dict(re.findall(r'<MLMesh label="([^"]+)"[^>]*>\s*<MLMatrix44>(.*?)</MLMatrix44>',
                            text, re.S))
    return {k: np.array(v.split(), float).reshape(4, 4) for k, v in found.items()}


def test_range_scans_pushed_to_a_clearance_of_one(tmp_path):
    """lato000 + lato180 placed by partial.mlp are about 0.83 apart; pushed
    to 1.0 between the layers, each written back in its own scanner frame."""
    require_shared_data()
    tau = 1.0
    M = scan_matrices()
    names = ["lato000.ply", "lato180.ply"]
    files = [DATA / "range_scans" / n for n in names]
    # partial.mlp lists twelve scans, ten of them absent here; the pair gets a
    # project of its own with the same matrices.
    mlp = project(tmp_path / "pair.mlp", [(f, M[n]) for f, n in zip(files, names)])
    outs = [tmp_path / "lato000_out.ply", tmp_path / "lato180_out.ply"]
    code, log, r = run_project(tmp_path, mlp, (ROOT / "samples" / "enforce_clearance.mlx")
                               .read_text().replace('name="report_file" value=""',
                                                    'name="report_file" value="{report0}"'),
                               outs)
    assert code == 0, log[-3000:]
    assert r["tau"] == tau and r["reached"], r
    assert 0.8 < r["min_distance_before"] < 0.86 and r["violating_pairs_before"] > 0
    assert r["min_distance_after"] >= tau and r["violating_pairs_after"] == 0
    # Independent check on the stored floats, placed by the matrices.
    A, FA = placed(outs[0], M[names[0]])
    B, FB = placed(outs[1], M[names[1]])
    before = min_distance_between(*placed(files[0], M[names[0]]), *placed(files[1], M[names[1]]),
                                  1.2)
    assert before == pytest.approx(r["min_distance_before"], rel=1e-5)
    found = min_distance_between(A, FA, B, FB, 1.2)
    diagonal = float(np.linalg.norm(np.vstack([A, B]).ptp(0)))
    assert found >= tau - rounding_tolerance(diagonal), (found, r)
    assert found == pytest.approx(r["min_distance_after"], rel=1e-5)
    assert r["max_displacement"] >= r["displacement_lower_bound"] * (1 - 1e-6)
    # Each scan keeps its connectivity and its own defects; no new crossings
    # within a scan or between the two (meshcheck on both placed in one file).
    for src, out in zip(files, outs):
        b, a = meshcheck(src), meshcheck(out)
        for key in ("vertices", "faces", "self_intersecting_pairs", "non_manifold_edges"):
            assert a[key] == b[key], (out.name, key)
    both = write_off(tmp_path / "placed_pair.off",
                     np.vstack([A, B]), np.vstack([FA, FB + len(A)]))
    assert meshcheck(both)["self_intersecting_pairs"] == 0
    # Vertices that did not move keep their stored coordinates bit for bit.
    moved = sum(int(np.count_nonzero(np.any(read_ply(o)[0] != read_ply(f)[0], axis=1)))
                for f, o in zip(files, outs))
    assert moved == r["vertices_moved"]


# ---- the paper's quantisation experiment on a real scan ----------------------

def read_obj(path):
    V, F = [], []
    for line in open(path):
        parts = line.split()
        if parts and parts[0] == "v":
            V.append(tuple(float(x) for x in parts[1:4]))
        elif parts and parts[0] == "f":
            F.append(tuple(int(p.split("/")[0]) - 1 for p in parts[1:4]))
    return V, F


def test_quantised_scan_pushed_back_to_tau(tmp_path):
    """spot.obj with its coordinates rounded to 9 bits of its diagonal, as a
    lossy codec would: non-adjacent faces come closer than tau = 0.004.
    Afterwards meshcheck's own minimum distance is at least tau (minus float
    rounding) and nothing intersects; the displacement stays of the order of
    what the worst pair needs."""
    require_shared_data()
    V, F = read_obj(DATA / "scanned/spot.obj")
    P = np.array(V)
    step = np.linalg.norm(P.max(axis=0) - P.min(axis=0)) / 512
    Q = np.round(P / step) * step
    src = write_off(tmp_path / "spot_quantised.off", [tuple(q) for q in Q], F)
    before = meshcheck(src, "--min-distance")
    assert before["self_intersecting_pairs"] == 0
    tau = 0.004
    assert before["min_distance"]["distance"] < tau
    out = tmp_path / "spot_out.ply"
    run = run_server(tmp_path, [src], enforce_script(tau=tau), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out, "--min-distance")
    assert r["reached"], r
    assert after["min_distance"]["distance"] >= tau - rounding_tolerance(after["bbox_diagonal"])
    assert after["self_intersecting_pairs"] == 0
    assert (after["faces"], after["border_edges"]) == (before["faces"], before["border_edges"])
    need = (tau - before["min_distance"]["distance"]) / 2
    assert need * (1 - 1e-6) <= r["max_displacement"] <= 3 * (tau - before["min_distance"]["distance"])


# ---- the paper's box and piston experiments ------------------------------------

def grid_box(n, half, center=(0.0, 0.0, 0.0), inward=False):
    """A closed box of half-size `half`, each side an n x n grid of squares
    cut in two (12 n^2 faces), its vertices shared along the edges."""
    index, V, F = {}, [], []

    def vertex(p):
        key = tuple(round(c * 1e9) for c in p)
        if key not in index:
            index[key] = len(V)
            V.append(tuple(center[k] + half * p[k] for k in range(3)))
        return index[key]

    for axis in range(3):
        for sign in (-1, 1):
            u, v = (axis + 1) % 3, (axis + 2) % 3

            def point(i, j):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = sign, -1 + 2 * i / n, -1 + 2 * j / n
                return vertex(p)

            for i in range(n):
                for j in range(n):
                    a, b, c, d = point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)
                    quad = [(a, b, c), (a, c, d)] if sign > 0 else [(a, c, b), (a, d, c)]
                    F += [(t[0], t[2], t[1]) for t in quad] if inward else quad
    return V, F


def cylinder(radius, height, segments, rings, center=(0.0, 0.0), inward=False):
    """A closed cylinder along z (two capped ends with a centre vertex)."""
    V = [(center[0] + radius * math.cos(2 * math.pi * s / segments),
          center[1] + radius * math.sin(2 * math.pi * s / segments), height * r / rings - height / 2)
         for r in range(rings + 1) for s in range(segments)]
    at = lambda r, s: r * segments + s % segments
    F = []
    for r in range(rings):
        for s in range(segments):
            F += [(at(r, s), at(r, s + 1), at(r + 1, s + 1)), (at(r, s), at(r + 1, s + 1), at(r + 1, s))]
    bottom, top = len(V), len(V) + 1
    V += [(center[0], center[1], -height / 2), (center[0], center[1], height / 2)]
    F += [(bottom, at(0, s + 1), at(0, s)) for s in range(segments)]
    F += [(top, at(rings, s), at(rings, s + 1)) for s in range(segments)]
    if inward:
        F = [(a, c, b) for a, b, c in F]
    return V, F


@pytest.mark.parametrize("case", ["layered box", "piston in cylinder"])
def test_paper_experiments_pushed_to_tau(tmp_path, case):
    """The paper's two synthetic experiments: a box whose inner skin comes
    within 0.02 of the outer one (1,176 faces, tau 0.03), and a piston in a
    bore with a too-tight fit (2,112 faces, tau 0.02). Checked by meshcheck."""
    if case == "layered box":
        V, F = combined(grid_box(7, 1.0), grid_box(7, 0.95, (0.03, 0.0, 0.0), inward=True))
        tau = 0.03
    else:
        V, F = combined(cylinder(0.5, 2.0, 48, 10, inward=True),
                        cylinder(0.49, 1.6, 48, 10, center=(0.005, 0.0)))
        tau = 0.02
    src = write_off(tmp_path / "parts.off", V, F)
    before = meshcheck(src, "--min-distance")
    assert before["self_intersecting_pairs"] == 0 and before["is_closed"]
    assert before["min_distance"]["distance"] < tau
    out = tmp_path / "out.ply"
    run = run_server(tmp_path, [src], enforce_script(tau=tau), outputs=[out])
    assert run.returncode == 0, run.log[-3000:]
    r, after = run.report, meshcheck(out, "--min-distance")
    assert r["reached"], r
    assert after["min_distance"]["distance"] >= tau - rounding_tolerance(after["bbox_diagonal"])
    assert after["self_intersecting_pairs"] == 0 and after["is_closed"]
    worst = before["min_distance"]["distance"]
    assert r["displacement_lower_bound"] == pytest.approx((tau - worst) / 2, rel=1e-3)
    assert (tau - worst) / 2 * (1 - 1e-6) <= r["max_displacement"] <= 2 * (tau - worst), r
    assert r["mean_displacement"] <= r["max_displacement"]
