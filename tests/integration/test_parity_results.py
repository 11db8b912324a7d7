"""Python parity (issue 40): the module's defaults give the filter's result.
Each filter runs through the real meshlabserver with every parameter at its
default (as `mlx` writes them from the plugin's declaration), and the
matching module function runs with no option at all, on the same file
(coordinates that are float values, so that the float host reads what the
module gets); the counts of the two reports agree. Parameter names and
defaults are compared in tests/python/test_parity.py."""
import sys

import numpy as np
import pytest

from conftest import BUILD, mlx, run_server, write_off

sys.path.insert(0, str(BUILD / "python"))
import meshmend as mm  # noqa: E402
from shapes import tube  # noqa: E402


def as_float(V):
    return np.asarray(V, float).astype(np.float32).astype(np.float64)


def crossing_tubes():
    """Two capped tubes crossing at right angles, in one mesh (one layer)."""
    (A, F), (B, G) = tube(0), tube(1, r=0.4)
    return as_float(np.vstack([A, B])), np.vstack([F, G + len(A)])


def open_tube():
    """A tube without its caps: two holes of 24 border edges."""
    V, F = tube(2)
    return as_float(V), F[: 2 * 24 * 4]


def through_the_filter(tmp_path, name, V, F):
    path = write_off(tmp_path / "input.off", V.tolist(), F.tolist())
    run = run_server(tmp_path, [path], mlx((name, {"report_file": "{report0}"})))
    assert run.returncode == 0, run.log[-3000:]
    return run.report


def same(theirs, ours, keys):
    for key in keys:
        assert theirs[key] == ours[key], (key, theirs[key], ours[key])


def test_inspect_with_the_defaults(tmp_path):
    V, F = crossing_tubes()
    theirs = through_the_filter(tmp_path, "MeshMend: Inspect Mesh Defects", V, F)
    ours = mm.inspect(V, F)
    assert ours["self_intersecting_pairs"] > 0  # counted by default, as the filter does
    same(theirs, ours, ["faces", "vertices", "border_edges", "is_closed", "connected_components",
                        "self_intersecting_pairs", "non_manifold_edges"])


def test_intersect_and_split_with_the_defaults(tmp_path):
    """The filter's default mode is the current layer's own intersections:
    split_self_intersections in the module."""
    V, F = crossing_tubes()
    theirs = through_the_filter(tmp_path, "MeshMend: Intersect and Split Layers", V, F)
    ours = mm.split_self_intersections(V, F).report
    assert ours["curve_edges"] > 0 and ours["remaining_intersecting_pairs"] == 0
    same(theirs, ours, ["curve_edges", "curve_loops", "faces_split", "duplicate_faces_removed",
                        "remaining_intersecting_pairs"])


def test_remove_self_intersections_with_the_defaults(tmp_path):
    V, F = crossing_tubes()
    theirs = through_the_filter(tmp_path, "MeshMend: Remove Self-Intersections", V, F)
    ours = mm.remove_self_intersections(V, F).report
    assert ours["remaining_intersecting_pairs"] == 0
    same(theirs, ours, ["faces_removed", "remaining_intersecting_pairs", "output_closed"])


def test_fill_holes_with_the_defaults(tmp_path):
    V, F = open_tube()
    theirs = through_the_filter(tmp_path, "MeshMend: Fill Holes (Feature Preserving)", V, F)
    ours = mm.fill_holes(V, F).report
    assert ours["holes_found"] == 2 and ours["holes_filled"] == 2
    same(theirs, ours, ["holes_found", "holes_filled", "holes_skipped", "faces_added",
                        "new_intersecting_pairs"])
