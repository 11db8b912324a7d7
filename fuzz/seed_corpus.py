#!/usr/bin/env python3
"""Writes the fuzz targets' seed inputs into OUT/<target>/: small meshes of
../shared/data (read here and encoded as fuzz/fuzz_input.h describes; the
files themselves are never copied into the repository), small OBJ files
from there for the OBJ reader, and a few shapes generated here (boxes in
contact on a grid). Run by scripts/fuzz before each run.

    seed_corpus.py SHARED_DATA_DIR OUT_DIR"""
import struct
import sys
from pathlib import Path

# Per target: (meshes per input, vertices and faces per mesh, leading option bytes).
MESH_TARGETS = {
    "mesh_validation": (1, 256, 512, 0),
    "remove_self_intersections": (1, 128, 256, 0),
    "fill_holes": (1, 128, 256, 0),
    "trim_stitch": (1, 128, 256, 0),
    "close_gaps": (1, 128, 256, 0),
    "split": (2, 96, 192, 1),
    "booleans": (2, 96, 192, 1),
    "clearance": (2, 64, 128, 0),
}
SINGLE = ["pairs/cube.obj", "pairs/xcylinder.obj", "pairs/sphere.obj", "pairs/eight.off",
          "pairs/decimated-knight.off", "self_intersecting/pig.off", "stitching/cgaltest_deg_border.off",
          "stitching/cgaltest_pinched.off", "stitching/quads_to_stitch.off", "holes/many_small_holes.ply"]
PAIRS = [("pairs/cube.obj", "pairs/sphere.obj"), ("pairs/xcylinder.obj", "pairs/ycylinder.obj"),
         ("pairs/ycylinder.obj", "pairs/zcylinder.obj"), ("pairs/sphere.obj", "pairs/xcylinder.obj")]
OBJ_FILES = ["pairs/cube.obj", "pairs/xcylinder.obj", "pairs/sphere.obj"]


def read_mesh(path):
    """Vertices and triangles (polygons fanned) of a small OFF, OBJ or ASCII PLY file."""
    text = path.read_text(errors="replace").splitlines()
    V, F = [], []
    if path.suffix.lower() == ".obj":
        for line in text:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                V.append(tuple(float(x) for x in w[1:4]))
            elif w[0] == "f":
                F.append([int(c.split("/")[0]) - 1 for c in w[1:]])
    elif path.suffix.lower() == ".off":
        words = " ".join(l.split("#")[0] for l in text).split()
        i = 1 if words[0].endswith("OFF") else 0
        nv, nf = int(words[i]), int(words[i + 1])
        i += 3
        for _ in range(nv):
            V.append(tuple(float(x) for x in words[i:i + 3]))
            i += 3
        for _ in range(nf):
            k = int(words[i])
            F.append([int(x) for x in words[i + 1:i + 1 + k]])
            i += 1 + k
    elif path.suffix.lower() == ".ply":
        if "format ascii" not in path.read_bytes()[:400].decode(errors="replace"):
            return None
        nv = nf = 0
        body = 0
        for n, line in enumerate(text):
            w = line.split()
            if w[:2] == ["element", "vertex"]:
                nv = int(w[2])
            if w[:2] == ["element", "face"]:
                nf = int(w[2])
            if w == ["end_header"]:
                body = n + 1
                break
        for line in text[body:body + nv]:
            V.append(tuple(float(x) for x in line.split()[:3]))
        for line in text[body + nv:body + nv + nf]:
            w = [int(x) for x in line.split()]
            F.append(w[1:1 + w[0]])
    T = [(f[0], f[i], f[i + 1]) for f in F for i in range(1, len(f) - 1)]
    return V, T


def part(V, T, max_vertices, max_faces):
    """The first faces of the mesh that fit the limits, re-indexed."""
    index, W, S = {}, [], []
    for t in T:
        new = [v for v in dict.fromkeys(t) if v not in index]
        if len(S) >= max_faces or len(W) + len(new) > max_vertices:
            break
        for v in new:
            index[v] = len(W)
            W.append(V[v])
        S.append(tuple(index[v] for v in t))
    return W, S


def encode(V, T, flags=0):
    out = bytes([flags, 2, 128]) + struct.pack("<H", len(V))
    for p in V:
        out += struct.pack("<3d", *p)
    for t in T:
        out += struct.pack("<3H", *t)
    return out


def grid_box(x0, y0, z0, s):
    """A box on the grid (signed bytes), 12 outward triangles."""
    V = [(x0 + s * (i & 1), y0 + s * (i >> 1 & 1), z0 + s * (i >> 2 & 1)) for i in range(8)]
    T = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4), (2, 6, 3), (3, 6, 7),
         (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]
    return V, T


def encode_grid(V, T, flags=0, exponent=128):
    out = bytes([flags, 0, exponent]) + struct.pack("<H", len(V))
    for p in V:
        out += struct.pack("<3b", *p)
    for t in T:
        out += struct.pack("<3H", *t)
    return out


def box_overlap(a, b):
    return all(min(p[k] for p in a) <= max(p[k] for p in b) and
               min(p[k] for p in b) <= max(p[k] for p in a) for k in range(3))


def main():
    data, out = Path(sys.argv[1]), Path(sys.argv[2])
    meshes = {}
    for name in set(SINGLE) | {n for p in PAIRS for n in p}:
        if (data / name).is_file():
            m = read_mesh(data / name)
            if m:
                meshes[name] = m
    written = 0

    def put(target, name, blob):
        nonlocal written
        folder = out / target
        folder.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(blob)
        written += 1

    # Two grid boxes: apart, sharing a face's plane, overlapping; the exponent spans scales.
    boxes = [grid_box(0, 0, 0, 8), grid_box(8, 0, 0, 8), grid_box(4, 4, 4, 8), grid_box(2, 2, 0, 4)]
    for target, (count, nv, nf, lead) in MESH_TARGETS.items():
        for name, (V, T) in meshes.items():
            W, S = part(V, T, nv, nf)
            put(target, Path(name).stem, bytes(lead) + encode(W, S) + (encode([], []) if count == 2 else b""))
        for (na, nb) in PAIRS:
            if count == 2 and na in meshes and nb in meshes:
                A, B = part(*meshes[na], nv, nf), part(*meshes[nb], nv, nf)
                put(target, Path(na).stem + "+" + Path(nb).stem, bytes(lead) + encode(*A) + encode(*B))
        for i, (a, b) in enumerate(zip(boxes, boxes[1:])):
            for exponent in (28, 128, 240):
                if count == 2:
                    blob = encode_grid(*a, exponent=exponent) + encode_grid(*b, exponent=exponent)
                else:
                    V = a[0] + b[0]
                    T = a[1] + [tuple(v + 8 for v in t) for t in b[1]]
                    blob = encode_grid(V, T, exponent=exponent)
                put(target, f"boxes{i}_e{exponent}", bytes(lead) + blob)

    # Triangle pairs whose boxes overlap, and one triangle with its neighbours' contacts.
    for (na, nb) in PAIRS:
        if na not in meshes or nb not in meshes:
            continue
        (VA, TA), (VB, TB) = meshes[na], meshes[nb]
        found = 0
        for ta in TA:
            pa = [VA[v] for v in ta]
            others = [[VB[v] for v in tb] for tb in TB if box_overlap(pa, [VB[v] for v in tb])]
            if not others:
                continue
            head = bytes([2, 0, 128])
            put("triangle_intersection", f"{Path(na).stem}_{found}",
                head + b"".join(struct.pack("<3d", *p) for p in pa + others[0]))
            put("retriangulate", f"{Path(na).stem}_{found}",
                head + b"".join(struct.pack("<3d", *p) for p in pa + sum(others[:8], [])))
            found += 1
            if found >= 6:
                break

    for name in OBJ_FILES:
        if (data / name).is_file():
            put("obj_reader", Path(name).stem, (data / name).read_bytes())
    put("obj_reader", "features",
        b"mtllib none.mtl\nv 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl a\n"
        b"f 1/1/1 2/1/1 3/1/1\nf -3 -2 -1\ng x\ns 1\nf 1 \\\n 2 3\n")
    print(f"{written} seed inputs in {out}")


if __name__ == "__main__":
    main()
