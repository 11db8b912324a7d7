"""Generated test meshes shared by the Python and meshlabserver test suites."""
import numpy as np


def tube(axis, n=24, rings=4, r=0.5, h=2.0):
    """A capped cylinder along `axis` (0, 1, 2), centred at the origin (as a
    CAD export has one): vertices (float array) and faces (int array)."""
    V = [(r * np.cos(2 * np.pi * j / n), r * np.sin(2 * np.pi * j / n), -h / 2 + h * k / rings)
         for k in range(rings + 1) for j in range(n)]
    F = []
    for k in range(rings):
        for j in range(n):
            a, b = k * n + j, k * n + (j + 1) % n
            F += [(a, b, b + n), (a, b + n, a + n)]
    V += [(0, 0, -h / 2), (0, 0, h / 2)]
    for j in range(n):
        F += [(len(V) - 2, (j + 1) % n, j), (len(V) - 1, rings * n + j, rings * n + (j + 1) % n)]
    turn = {0: [2, 0, 1], 1: [1, 2, 0], 2: [0, 1, 2]}[axis]  # cyclic: orientation kept
    return np.array(V)[:, turn], np.array(F, dtype=np.int64)


def write_off(path, V, F):
    """A mesh as an OFF file (triangles or polygons), coordinates written
    exactly (repr). Returns the path."""
    with open(path, "w") as f:
        f.write(f"OFF\n{len(V)} {len(F)} 0\n")
        for v in V:
            f.write(" ".join(repr(float(c)) for c in v) + "\n")
        for t in F:
            f.write(f"{len(t)} " + " ".join(str(int(i)) for i in t) + "\n")
    return path
