"""CAD-like cases generated here (never copied from elsewhere) for the output
stage's tests through every host: parts a hair apart at large coordinates,
coincident and coplanar faces, parts sharing whole faces, faces meeting at
1e-10 degrees, coordinates up to 1e30 and near FLT_MAX, and chains of
booleans. Each case is a list of closed, consistently oriented parts, each
(vertices float64 (n, 3), faces int64 (m, 3)), in double precision: a float
host reads them rounded to float, as it reads any file."""
import numpy as np

from shapes import tube


def box(lo, hi, n=2):
    """A closed box from corner `lo` to `hi` whose every side is an n x n
    grid of squares, each cut into two triangles (as CAD exports tessellate
    planar faces), outward facing."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    V, F, index = [], [], {}

    def vertex(i, j, k):
        key = (i, j, k)
        if key not in index:
            index[key] = len(V)
            t = np.array([i, j, k], float) / n
            V.append(lo + t * (hi - lo))
        return index[key]

    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, n):
            for a in range(n):
                for b in range(n):
                    quad = []
                    for da, db in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        c = [0, 0, 0]
                        c[axis], c[u], c[w] = side, a + da, b + db
                        quad.append(vertex(*c))
                    if side == 0:  # outward = -axis: reverse the (u, w) turn
                        quad = quad[::-1]
                    F += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    return np.array(V), np.array(F, dtype=np.int64)


def rotated(mesh, axis, degrees, centre):
    """The mesh turned by `degrees` about `axis` (any direction) through
    `centre` (Rodrigues' formula, in double)."""
    V, F = mesh
    k = np.asarray(axis, float)
    k = k / np.linalg.norm(k)
    theta = np.radians(degrees)
    c, s = np.cos(theta), np.sin(theta)
    p = V - centre
    out = p * c + np.cross(k, p) * s + np.outer(p @ k, k) * (1 - c)
    return out + centre, F


def moved(mesh, offset):
    V, F = mesh
    return V + np.asarray(offset, float), F


def scaled(mesh, factor):
    V, F = mesh
    return V * factor, F


def offset_parts():
    """A CAD part near coordinates 1e4 and its copy 1e-8 away along all
    three axes (a relative offset of 1e-12): every side of one crosses the
    sides of the other within a hair of the box's edges."""
    a = box((1e4, 1e4, 1e4), (1e4 + 20, 1e4 + 10, 1e4 + 5), n=3)
    return [a, moved(a, (1e-8, 0.7e-8, 0.4e-8))]


def coplanar_parts():
    """Two blocks whose bottom and top faces lie in the same planes and
    overlap in part (coincident and coplanar faces between parts)."""
    a = box((1e4, 1e4, 1e4), (1e4 + 4, 1e4 + 4, 1e4 + 2), n=2)
    b = box((1e4 + 2, 1e4 + 1, 1e4), (1e4 + 6, 1e4 + 3, 1e4 + 2), n=2)
    return [a, b]


def shared_face_parts():
    """Two blocks side by side sharing a whole face, with the same
    tessellation there (the same vertices, as an assembly exports them)."""
    a = box((0, 0, 0), (1, 1, 1), n=2)
    b = box((1, 0, 0), (2, 1, 1), n=2)
    return [moved(a, (1e4, 1e4, 1e4)), moved(b, (1e4, 1e4, 1e4))]


def near_parallel_parts(degrees=1e-10):
    """A block and its copy turned by `degrees` about a skew axis through
    its centre: faces meeting at 1e-10 degrees, nearly coincident all over."""
    a = box((1e4, 1e4, 1e4), (1e4 + 8, 1e4 + 6, 1e4 + 4), n=2)
    centre = np.array([1e4 + 4, 1e4 + 3, 1e4 + 2])
    return [a, rotated(a, (1, 2, 3), degrees, centre)]


def crossing_tubes(scale):
    """Two capped cylinders crossing at right angles, scaled by `scale`."""
    return [scaled(tube(0, n=12, rings=2), scale), scaled(tube(1, n=12, rings=2), scale)]


def huge_parts():
    """Coordinates up to 1e30."""
    return crossing_tubes(1e30)


def near_flt_max_parts():
    """Coordinates up to 3e38, just under FLT_MAX (3.4028e38): what a float
    host can still hold, and beyond which any sum of two overflows."""
    return crossing_tubes(3e38)


CASES = {
    "offset_1e-8_at_1e4": offset_parts,
    "coplanar_faces": coplanar_parts,
    "shared_faces": shared_face_parts,
    "near_parallel_1e-10_deg": near_parallel_parts,
    "coordinates_1e30": huge_parts,
    "near_flt_max": near_flt_max_parts,
}


def union_tiles(count=10):
    """A part and copies moved by 0.6 of its length each time (an array of
    tiles), each overlapping the one before: the chained unions."""
    tile = box((1e4, 1e4, 1e4), (1e4 + 10, 1e4 + 7, 1e4 + 3), n=2)
    return tile, [moved(tile, (6.0 * (i + 1), 0.3 * (i + 1), 0.1 * (i + 1))) for i in range(count)]


def drill_holes(count=10):
    """A plate and drills (cylinders through it) one after another: the
    chained differences."""
    plate = box((1e4, 1e4, 1e4), (1e4 + 40, 1e4 + 10, 1e4 + 4), n=2)
    drills = []
    for i in range(count):
        V, F = tube(2, n=10, rings=1, r=1.2, h=8)
        drills.append((V + np.array([1e4 + 2.5 + 3.7 * i, 1e4 + 5 + 0.2 * i, 1e4 + 2]), F))
    return plate, drills
