"""Generated meshes of the classes that break repair filters on CAD exports
and broken scans (issue 42), shared by the meshlabserver and pymeshlab
suites: coordinates from 1e-30 to near FLT_MAX, coplanar contact between
parts, non-manifold and inconsistently oriented exports, STL soups with
T-junctions, walls with holes, spindle and self-touching tori, and a
heavily self-intersecting OpenSCAD-like export. Every mesh is made here:
vertices (float64 array) and triangles (int64 array)."""
import math

import numpy as np

from shapes import write_off  # noqa: F401 (the suites write the classes with it)

BOX_FACES = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4), (2, 6, 3), (3, 6, 7),
             (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]


def box(lo=(0, 0, 0), hi=(1, 1, 1)):
    """An axis-aligned box with outward faces, 12 triangles."""
    V = [(hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
         for i in range(8)]
    return np.array(V, float), np.array(BOX_FACES, np.int64)


def combined(*meshes):
    """The meshes in one (indices offset), as an export writes separate solids."""
    V, F, n = [], [], 0
    for v, f in meshes:
        V.append(np.asarray(v, float))
        F.append(np.asarray(f, np.int64) + n)
        n += len(v)
    return np.vstack(V), np.vstack(F)


def cylinder(center, radius, height, n=16, axis=2):
    """A closed capped cylinder along `axis`, outward faces."""
    cx, cy, cz = center
    V = []
    for z in (-height / 2, height / 2):
        for j in range(n):
            a = 2 * math.pi * j / n
            V.append((radius * math.cos(a), radius * math.sin(a), z))
    V += [(0, 0, -height / 2), (0, 0, height / 2)]
    F = []
    for j in range(n):
        a, b = j, (j + 1) % n
        F += [(a, b, b + n), (a, b + n, a + n), (2 * n, b, a), (2 * n + 1, a + n, b + n)]
    V = np.array(V)[:, {0: [2, 0, 1], 1: [1, 2, 0], 2: [0, 1, 2]}[axis]] + (cx, cy, cz)
    return V, np.array(F, np.int64)


def torus(R, r, around=48, tube=24, squeeze=1.0):
    """A torus around z (outward faces where R > r). R < r: a spindle torus,
    every meridian through the two points where the tube meets the axis
    (none of them a vertex); R == r: a horn torus, touching itself at the
    centre; squeeze < 1 flattens it along y until its walls press together."""
    V = []
    for i in range(around):
        u = 2 * math.pi * i / around
        for j in range(tube):
            v = 2 * math.pi * j / tube
            rad = R + r * math.cos(v)
            V.append((rad * math.cos(u), rad * math.sin(u) * squeeze, r * math.sin(v)))
    at = lambda i, j: (i % around) * tube + j % tube
    F = []
    for i in range(around):
        for j in range(tube):
            F += [(at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))]
    return np.array(V), np.array(F, np.int64)


def scaled(mesh, scale, offset=(0, 0, 0)):
    V, F = mesh
    return np.asarray(V, float) * scale + offset, F


def soup(mesh):
    """Every triangle with its own three vertices, as an STL stores them."""
    V, F = mesh
    return np.asarray(V, float)[np.asarray(F).reshape(-1)], np.arange(3 * len(F)).reshape(-1, 3)


def flipped(mesh, faces):
    V, F = mesh
    F = np.array(F)
    F[faces] = F[faces][:, ::-1]
    return V, F


def box_with_t_junctions():
    """A unit box whose top is cut into four triangles around a point on an
    edge it shares with an uncut side: that side's face has a vertex in the
    middle of its edge (a T-junction), as CAD exports mesh adjacent faces."""
    V, F = box()
    V = np.vstack([V, [(0.5, 0.0, 1.0)]])  # 8: middle of the top's edge y=0
    top = [i for i, f in enumerate(F) if all(V[v][2] == 1 for v in f)]
    F = [tuple(f) for i, f in enumerate(F) if i not in top]
    F += [(4, 8, 6), (8, 7, 6), (8, 5, 7)]  # the top (4 5 7 6), fanned from the T point
    return V, np.array(F, np.int64)


def wall_with_hole(open_side=False):
    """A wall 4 x 4 x 1 with a square hole 2 x 2 through it: closed, genus 1
    (with open_side, the faces lining one side of the hole are left out)."""
    V, F = [], []

    def quad(a, b, c, d):
        n = len(V)
        V.extend([a, b, c, d])
        F.extend([(n, n + 1, n + 2), (n, n + 2, n + 3)])

    for z, turn in ((0, -1), (1, 1)):
        ring = [(0, 0), (4, 0), (4, 4), (0, 4)]
        hole = [(1, 1), (3, 1), (3, 3), (1, 3)]
        for k in range(4):
            p, q, s, t = ring[k], ring[(k + 1) % 4], hole[(k + 1) % 4], hole[k]
            pts = [(*p, z), (*q, z), (*s, z), (*t, z)]
            quad(*(pts if turn > 0 else pts[::-1]))
    outer = [(0, 0), (4, 0), (4, 4), (0, 4)]
    inner = [(1, 1), (3, 1), (3, 3), (1, 3)]
    for k in range(4):
        p, q = outer[k], outer[(k + 1) % 4]
        quad((*p, 0), (*q, 0), (*q, 1), (*p, 1))
        if open_side and k == 0:
            continue
        p, q = inner[k], inner[(k + 1) % 4]
        quad((*q, 0), (*p, 0), (*p, 1), (*q, 1))
    return weld(np.array(V, float), np.array(F, np.int64))


def weld(V, F):
    """Vertices with equal coordinates merged."""
    keys, index = {}, []
    for p in map(tuple, V):
        index.append(keys.setdefault(p, len(keys)))
    W = np.array(sorted(keys, key=keys.get), float)
    return W, np.array(index)[F]


def openscad_export(parts=24, seed=7):
    """Boxes and cylinders placed on a coarse grid, overlapping each other
    and sharing face planes, written as one mesh without any boolean (an
    OpenSCAD-like union exported naively): each part closed and outward,
    the whole consistently oriented and heavily self-intersecting."""
    rng = np.random.default_rng(seed)
    meshes = []
    for k in range(parts):
        lo = rng.integers(0, 6, 3).astype(float)
        if k % 3 == 2:
            meshes.append(cylinder(lo + 1, float(rng.integers(1, 3)) * 0.5, float(rng.integers(2, 5)),
                                   n=12, axis=int(rng.integers(0, 3))))
        else:
            meshes.append(box(lo, lo + rng.integers(1, 4, 3)))
    return combined(*meshes)


def coplanar_parts():
    """Two boxes in one layer that share part of a face's plane: one sits on
    the other (touching), and a third overlaps the second with coplanar sides."""
    return combined(box((0, 0, 0), (2, 2, 1)), box((0.5, 0.5, 1), (1.5, 1.5, 2)),
                    box((0.5, 0, 0), (2.5, 1, 1)))


def non_manifold_export():
    """Two boxes sharing one edge (four faces on it once welded) and a fin:
    a triangle hanging from an edge of a third box."""
    a, b = box((0, 0, 0), (1, 1, 1)), box((1, 1, 0), (2, 2, 1))
    c = box((3, 0, 0), (4, 1, 1))
    V, F = combined(a, b, c)
    V = np.vstack([V, [(3.5, -1.0, 0.5)]])
    F = np.vstack([F, [(16, 17, len(V) - 1)]])  # on edge (3,0,0)-(4,0,0) of c
    return weld(V, F)


def classes():
    """Every generated class: name -> (V, F)."""
    t = torus(1.0, 0.4, 32, 16)
    return {
        "tiny_1e-30": scaled(t, 1e-30),
        "huge_1e37": scaled(t, 1e37),
        "part_in_flt_max_box": combined(t, box((-3.4e38,) * 3, (3.4e38,) * 3)),
        "coplanar_parts": coplanar_parts(),
        "non_manifold_export": non_manifold_export(),
        "inconsistently_oriented": flipped(box(), [0, 5]),
        "stl_soup_t_junctions": soup(box_with_t_junctions()),
        "wall_with_hole": wall_with_hole(),
        "wall_with_open_hole": wall_with_hole(open_side=True),
        "spindle_torus": torus(0.3, 1.0, 64, 32),
        "horn_torus": torus(1.0, 1.0, 48, 24),
        "squeezed_torus": torus(1.0, 0.5, 48, 24, squeeze=0.25),
        "openscad_export": openscad_export(),
    }


if __name__ == "__main__":
    import sys
    from pathlib import Path
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    for name, (V, F) in classes().items():
        write_off(out / f"{name}.off", V, F)
        print(name, len(V), len(F))
