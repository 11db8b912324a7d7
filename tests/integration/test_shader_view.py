"""MeshMend: Prepare Shader View through meshlabserver: the values the
shaders in shaders/ read (common/render/render_channels.h), written as per-wedge
texture coordinates, saved to PLY and decoded here as the shaders decode
them, against values computed independently (vertex quality, face quality,
boundaries from the saved faces, the faces a filter added)."""
import json
import subprocess

import numpy as np
import pytest

from conftest import ROOT, cube, mlx, write_off

PREPARE = "MeshMend: Prepare Shader View"
CLEARANCE, PATCHES, FACE_CHANGES = 0, 1, 2


def server(tmp_path, inputs, script, out=None, flags=("wt",)):
    """scripts/meshlabserver; the output saved with the given -m flags."""
    path = tmp_path / "script.mlx"
    path.write_text(script)
    cmd = [str(ROOT / "scripts" / "meshlabserver")]
    for i in inputs:
        cmd += ["-i", str(i)]
    cmd += ["-s", str(path)]
    if out:
        cmd += ["-o", str(out), "-m", *flags]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    return proc.returncode, proc.stdout + proc.stderr


_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4",
          "float": "f4", "double": "f8"}


def read_faces(path):
    """Binary PLY: vertex table (dict of arrays), and per face its corners,
    texture coordinates (3 x 2) and quality when present."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    elements = []
    for line in data[:end].decode("ascii").splitlines():
        w = line.split()
        if w[0] == "format":
            assert w[1] == "binary_little_endian", w
        elif w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property":
            elements[-1][2].append(w[1:])
    pos, vertices, faces = end, None, {"corners": [], "texcoord": [], "quality": []}
    for name, count, props in elements:
        if name == "vertex":
            dtype = np.dtype([(p[1], "<" + _TYPES[p[0]]) for p in props])
            vertices = np.frombuffer(data, dtype, count, pos)
            pos += dtype.itemsize * count
            continue
        for _ in range(count):
            for p in props:
                if p[0] == "list":
                    ct, it = np.dtype("<" + _TYPES[p[1]]), np.dtype("<" + _TYPES[p[2]])
                    k = int(np.frombuffer(data, ct, 1, pos)[0])
                    pos += ct.itemsize
                    values = np.frombuffer(data, it, k, pos)
                    pos += it.itemsize * k
                    key = "corners" if p[3] == "vertex_indices" else p[3]
                    faces[key].append(values)
                else:
                    t = np.dtype("<" + _TYPES[p[0]])
                    faces[p[1]].append(np.frombuffer(data, t, 1, pos)[0])
                    pos += t.itemsize
    return vertices, {k: np.array(v) for k, v in faces.items() if v}


def decode(u, v):
    """What the shaders compute from an interpolated (u, v) (float32 arithmetic)."""
    u, v = np.float32(u), np.float32(v)
    tag = np.floor(v / np.float32(100) + np.float32(0.5)) * np.float32(100)
    rest = v - tag
    mask = np.floor(rest / np.float32(4) + np.float32(0.375))
    label = np.floor(u / np.float32(4) + np.float32(0.375))
    return int(tag), int(label), int(mask), float(u - 4 * label), float(rest - 4 * mask)


def boundary_masks(F, labels, borders):
    """Independently: bit k of face f when its edge k (corner k to k+1) has a
    face of another label across, or (borders) no face across."""
    uses = {}
    for f, t in enumerate(F):
        for k in range(3):
            uses.setdefault(frozenset((int(t[k]), int(t[(k + 1) % 3]))), []).append((f, k))
    masks = np.zeros(len(F), int)
    for faces in uses.values():
        if len({labels[f] for f, _ in faces}) > 1 or (borders and len(faces) == 1):
            for f, k in faces:
                masks[f] |= 1 << k
    return masks


def check_labels(F, T, labels, tag, borders):
    """Every corner decodes to the face's label, the expected boundary mask
    and its own barycentric corner; the fragment at the centroid as well."""
    masks = boundary_masks(F, labels, borders)
    corners = [(1, 0), (0, 1), (0, 0)]
    for f in range(len(F)):
        for k in range(3):
            got = decode(*T[f][2 * k:2 * k + 2])
            assert got == (tag, labels[f] % 1024, masks[f], *corners[k]), (f, k, got)
        center = decode(np.float32(T[f][0::2].sum() / 3), np.float32(T[f][1::2].sum() / 3))
        assert center[:3] == (tag, labels[f] % 1024, masks[f])
        assert center[3] == pytest.approx(1 / 3, abs=1e-3) and center[4] == pytest.approx(1 / 3, abs=1e-3)
    return masks


def shifted(V, d):
    return [(x + d, y + d, z + d) for x, y, z in V]


def test_clearance_values_are_the_vertex_quality(tmp_path):
    """Two parallel boxes 0.1 apart: Measure Clearance sets vertex quality,
    Prepare Shader View puts it on every corner (v = 100)."""
    V, F = cube()
    V2 = [(x, y, z + 1.1) for x, y, z in V]
    src = write_off(tmp_path / "two.off", V + V2, F + [tuple(i + 8 for i in t) for t in F])
    out = tmp_path / "out.ply"
    code, log = server(tmp_path, [src], mlx(("MeshMend: Measure Clearance", {"tau": 0.2}),
                                            (PREPARE, {"values": CLEARANCE})), out, ("wt", "vq"))
    assert code == 0, log[-3000:]
    vertices, faces = read_faces(out)
    quality = vertices["quality"]
    assert quality.min() == pytest.approx(0.1, rel=1e-5)
    T = faces["texcoord"]
    for f, corners in enumerate(faces["corners"]):
        for k, v in enumerate(corners):
            assert T[f][2 * k] == quality[v] and T[f][2 * k + 1] == 100, (f, k)
    assert "meshmend_clearance.gdp" in log


def test_patch_ids_and_boundaries(tmp_path):
    """Two crossing cubes split and painted (samples/paint_patches.mlx): each
    face decodes to its patch id (the saved face quality), with the edges to
    other patches and the borders as boundaries."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", shifted(V, 0.5), F)
    paint = (ROOT / "samples" / "paint_patches.mlx").read_text()
    script = paint.replace("</FilterScript>", "") + \
        mlx((PREPARE, {"values": PATCHES})).split("<FilterScript>")[1]
    out = tmp_path / "painted.ply"
    code, log = server(tmp_path, [a, b], script, out, ("wt", "fq"))
    assert code == 0, log[-3000:]
    _, faces = read_faces(out)
    F, T = faces["corners"], faces["texcoord"]
    ids = faces["quality"].astype(int)
    assert len(set(ids)) == 4  # each cube cut in two by the other
    masks = check_labels(F, T, ids, 200, borders=True)
    assert (masks != 0).sum() > 0 and (masks == 0).sum() > 0

    # A saved painted mesh (ids only in the face quality) can be prepared again.
    again = tmp_path / "again.ply"
    code, log = server(tmp_path, [out], mlx((PREPARE, {"values": PATCHES})), again, ("wt", "fq"))
    assert code == 0, log[-3000:]
    assert "ids from the face quality" in log
    _, faces2 = read_faces(again)
    assert np.array_equal(faces2["texcoord"], T)


def corners_key(P):
    """A face by its corner coordinates, in any order."""
    return tuple(sorted(tuple(map(float, p)) for p in P))


def test_faces_made_by_hole_filling(tmp_path):
    """A cube with one side missing: Fill Holes adds faces, which decode as
    new (2); the input faces as kept (0); the region of new faces outlined."""
    V, F = cube()
    kept = F[2:]  # the z = 0 side removed
    src = write_off(tmp_path / "open.off", V, kept)
    out = tmp_path / "filled.ply"
    report = tmp_path / "report.json"
    script = mlx(("MeshMend: Fill Holes (Feature Preserving)",
                  {"max_diameter": 0, "report_file": str(report)}),
                 (PREPARE, {"values": FACE_CHANGES}))
    code, log = server(tmp_path, [src], script, out)
    assert code == 0, log[-3000:]
    added = json.loads(report.read_text())["faces_added"]
    vertices, faces = read_faces(out)
    F2, T = faces["corners"], faces["texcoord"]
    P = np.stack([vertices["x"], vertices["y"], vertices["z"]], 1)
    old = {corners_key(np.array(V, float)[list(t)]) for t in kept}
    labels = np.array([0 if corners_key(P[t]) in old else 2 for t in F2])
    assert (labels == 2).sum() == added > 0
    check_labels(F2, T, labels, 300, borders=False)


@pytest.mark.parametrize("values,message", [
    (CLEARANCE, "has no vertex quality: run MeshMend: Measure Clearance first"),
    (PATCHES, "has no patch ids: run MeshMend: Paint Surface Patches first"),
    (FACE_CHANGES, "has no record of the faces a MeshMend filter made")])
def test_missing_values_are_named(tmp_path, values, message):
    src = write_off(tmp_path / "cube.off", *cube())
    out = tmp_path / "out.ply"
    code, log = server(tmp_path, [src], mlx((PREPARE, {"values": values})), out)
    assert code != 0 and message in log, log[-2000:]
    assert not out.exists()


def test_own_texture_coordinates_are_not_overwritten(tmp_path):
    """A layer with texture coordinates of its own is refused, and says how
    to prepare a copy."""
    V, F = cube()
    src = tmp_path / "textured.ply"
    with open(src, "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\n"
                "property float y\nproperty float z\nproperty float quality\n"
                f"element face {len(F)}\nproperty list uchar int vertex_indices\n"
                "property list uchar float texcoord\nend_header\n")
        for v in V:
            f.write("%g %g %g 1\n" % v)
        for t in F:
            f.write("3 %d %d %d 6 0.1 0.2 0.3 0.4 0.5 0.6\n" % t)
    out = tmp_path / "out.ply"
    code, log = server(tmp_path, [src], mlx((PREPARE, {"values": CLEARANCE})), out)
    assert code != 0, log[-2000:]
    assert "has texture coordinates of its own" in log and "Duplicate Current Layer" in log
    assert not out.exists()
