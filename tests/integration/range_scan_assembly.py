"""A trim-and-stitch assembly of two real range scans: lato000 and lato180
of ../shared/data/range_scans (opposite sides of one object, aligned by
partial.mlp, their borders about 50 units apart across the unscanned flank).
Each scan's ragged border facing the other is trimmed away along a cut
through the inside ("MeshMend: Trim Along Vertex Loop"), and the two cuts are
stitched, with subdivision, into one part ("MeshMend: Stitch Boundaries"),
all in one meshlabserver run. Used by test_stitch.py (which checks the
result) and by scripts/pictures (which draws it):

    python3 range_scan_assembly.py OUT_DIR   # a.off, b.off, both.off (the two in one
                                             # file), assembled.ply, script.mlx
"""
import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from conftest import DATA, mlx, read_ply, run_server, write_off

TRIM = "MeshMend: Trim Along Vertex Loop"
STITCH = "MeshMend: Stitch Boundaries"


def indices(xs):
    return " ".join(map(str, xs))


def mlp_matrices(path):
    root = ET.parse(path).getroot()
    out = {}
    for mesh in root.iter("MLMesh"):
        values = [float(x) for x in mesh.find("MLMatrix44").text.split()]
        out[mesh.get("label")] = [values[4 * r:4 * r + 4] for r in range(4)]
    return out


def main_component(V, F):
    """The largest vertex-connected part, compacted."""
    parent = np.arange(len(V))

    def root(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for a, b, c in F:
        ra = root(a)
        parent[root(b)] = ra
        parent[root(c)] = ra
    roots = np.array([root(t[0]) for t in F])
    values, counts = np.unique(roots, return_counts=True)
    F = F[roots == values[counts.argmax()]]
    used = np.unique(F)
    remap = -np.ones(len(V), int)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def border_edges(F):
    """Directed border edges (used by one face), in their face's direction."""
    uses = set()
    for a, b, c in F:
        uses.update(((a, b), (b, c), (c, a)))
    return [(u, v) for (u, v) in uses if (v, u) not in uses]


def adjacency(pairs):
    out = {}
    for u, v in pairs:
        out.setdefault(u, set()).add(v)
        out.setdefault(v, set()).add(u)
    return out


def mesh_adjacency(F):
    return adjacency((u, v) for a, b, c in F for u, v in ((a, b), (b, c), (c, a)))


def outer_border(F):
    """The vertices and edges of the largest connected set of border edges
    (a scan's outer border, pinch vertices included)."""
    edges = border_edges(F)
    parent = {}

    def root(x):
        while parent.get(x, x) != x:
            x = parent[x]
        return x
    for u, v in edges:
        ru, rv = root(u), root(v)
        if ru != rv:
            parent[ru] = rv
    sizes = {}
    for u, _ in edges:
        sizes[root(u)] = sizes.get(root(u), 0) + 1
    biggest = max(sizes, key=sizes.get)
    outer = [(u, v) for u, v in edges if root(u) == biggest]
    return sorted({x for e in outer for x in e}), outer


def shortest_path(V, adj, sources, target=None, allowed=None, cost=None, limit=math.inf):
    """Dijkstra along edges (length x cost(vertex entered)) from the sources:
    distances, and the path to `target` when given."""
    import heapq
    dist, came = {s: 0.0 for s in sources}, {}
    queue = [(0.0, s) for s in sources]
    heapq.heapify(queue)
    while queue:
        d, u = heapq.heappop(queue)
        if u == target:
            break
        if d > dist[u]:
            continue
        for w in adj.get(u, ()):
            if allowed and not allowed(w):
                continue
            nd = d + float(((V[u] - V[w]) ** 2).sum() ** 0.5) * (cost(w) if cost else 1.0)
            if nd < dist.get(w, math.inf) and nd <= limit:
                dist[w], came[w] = nd, u
                heapq.heappush(queue, (nd, w))
    if target is None:
        return dist
    assert target in dist, "no path"
    path = [target]
    while path[-1] not in sources:
        path.append(came[path[-1]])
    return path[::-1]


def facing_cut(V, F, other_border_points, bound):
    """A trim loop that cuts away a scan's ragged border where it faces the
    other scan: the part of the outer border within `bound` of the other
    scan's border runs from s to t (the two such vertices farthest apart,
    each with interior neighbours); the cut goes back from s to t through
    the inside, away from every border (entering no border vertex, and
    paying ten times the length within four edge lengths of one), so that
    after the trim the whole cut is border. Returns the loop (cut, then the
    border back), the cut, and a face far from the cut on the kept side."""
    border, outer = outer_border(F)
    every_border = {x for e in border_edges(F) for x in e}
    adj = mesh_adjacency(F)
    B = np.array(border)
    gap = np.sqrt(((V[B][:, None, :] - other_border_points[None, :, :]) ** 2).sum(-1)).min(1)
    facing = [int(v) for v in B[gap < bound] if sum(w not in every_border for w in adj[v]) >= 2]
    P = V[facing]
    i, j = np.unravel_index(np.argmax(((P[:, None] - P[None]) ** 2).sum(-1)), (len(P), len(P)))
    s, t = facing[i], facing[j]
    run = shortest_path(V, adjacency(outer), [t], target=s)  # t .. s along the border
    edge = np.mean([((V[u] - V[v]) ** 2).sum() ** 0.5 for u, v in outer])
    reach = 4 * edge
    near_border = shortest_path(V, adj, list(every_border), limit=reach)
    cut = shortest_path(V, adj, [s], target=t, allowed=lambda w: w not in every_border or w == t,
                        cost=lambda w: 1 + 10 * max(0.0, reach - near_border.get(w, reach)) / reach)
    loop = cut + run[1:-1]
    centre = V[cut].mean(0)
    far = int(np.argmax(((V[F].mean(1) - centre) ** 2).sum(-1)))
    return loop, cut, far


def assemble(workdir):
    """Writes the two aligned scans (their largest parts) to workdir/a.off and
    b.off, trims and stitches them by meshlabserver into
    workdir/assembled.ply. Returns the run (its reports: trim a, trim b,
    stitch), the output path, the cuts (vertex indices in each scan) and the
    number of vertices of the first scan (the second's indices follow)."""
    workdir = Path(workdir)
    scans = DATA / "range_scans"
    matrices = mlp_matrices(scans / "partial.mlp")
    parts = []
    for name in ("lato000.ply", "lato180.ply"):
        V, F, _ = read_ply(scans / name)
        m = np.array(matrices[name])
        V = np.array(V, float) @ m[:3, :3].T + m[:3, 3]  # the layer matrix, applied here
        parts.append(main_component(V, np.array(F)))
    borders = [V[outer_border(F)[0]] for V, F in parts]
    closest = np.sqrt(((borders[0][:, None, :] - borders[1][None, :, :]) ** 2).sum(-1)).min()
    bound = closest + 12
    files, loops, cuts, keep = [], [], [], []
    for (V, F), other, name in zip(parts, borders[::-1], ("a", "b")):
        loop, cut, far = facing_cut(V, F, other, bound)
        loops.append(loop)
        cuts.append(cut)
        keep.append(far)
        files.append(write_off(workdir / f"{name}.off", V.tolist(), F.tolist()))

    def trim(k, report):
        return (TRIM, {"loop_vertices": indices(loops[k]), "keep_side": 1, "keep_face": keep[k],
                       "remove_unreferenced_vertices": False, "report_file": report})
    stitch = (STITCH, {"paths_from": 1, "first_layer": 0, "second_layer": 1,
                       "path_a": indices(cuts[0]), "path_b": indices(cuts[1]),
                       "max_aspect_ratio": 3, "report_file": "{report2}"})
    # Between the trims, MeshLab's "Change the current layer" step
    # (meshlabserver's current layer is the last one loaded).
    change = (' <filter name="Change the current layer">\n  <Param type="RichMesh" value="{}" '
              'name="layer" description="" tooltip=""/>\n </filter>\n')
    body = lambda *steps: mlx(*steps).split("<FilterScript>\n")[1].split("</FilterScript>")[0]
    script = ("<!DOCTYPE FilterScript>\n<FilterScript>\n" + change.format(0) +
              body(trim(0, "{report0}")) + change.format(1) + body(trim(1, "{report1}")) +
              body(stitch) + "</FilterScript>\n")
    out = workdir / "assembled.ply"
    run = run_server(workdir, files, script, outputs=[out])
    return SimpleNamespace(run=run, output=out, files=files, parts=parts, cuts=cuts,
                           offset=len(parts[0][0]))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: range_scan_assembly.py OUT_DIR")
    result = assemble(sys.argv[1])
    if result.run.returncode != 0 or len(result.run.reports) != 3:
        sys.exit("the assembly failed:\n" + result.run.log[-3000:])
    trim_a, trim_b, stitched = result.run.reports
    (Va, Fa), (Vb, Fb) = result.parts
    write_off(Path(sys.argv[1]) / "both.off", np.vstack([Va, Vb]).tolist(),
              np.vstack([Fa, Fb + len(Va)]).tolist())
    print(f"trimmed {trim_a['faces_removed']} + {trim_b['faces_removed']} faces; stitched "
          f"{stitched['faces_added']} faces, {stitched['vertices_added']} new vertices; border "
          f"edges {stitched['border_edges_before']} -> {stitched['border_edges_after']}")
