"""A refusal leaves the layers as they were, and nothing to do is success,
in MeshLab 2020.09's own types (float): each filter runs in plugin_apply
(tests/plugin_apply.cpp), a one-filter host that saves every layer after
the filter whether it succeeded or not (meshlabserver saves nothing after
a failed filter), and the layers saved are compared with the input
exactly. The inputs are the generated classes of tests/robustness_shapes.py."""
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import BUILD, PLUGIN_DIR, ROOT, cube, probe

sys.path.append(str(ROOT / "tests"))
import robustness_shapes  # noqa: E402

CLASSES = robustness_shapes.classes()
REMOVE = "MeshMend: Remove Self-Intersections"
SPLIT = "MeshMend: Intersect and Split Layers"
FILL = "MeshMend: Fill Holes (Feature Preserving)"
CLOSE = "MeshMend: Close Gaps Between Borders"
SECONDS = 60


def plugin_of(filter_name):
    for p in probe():
        if any(f["name"] == filter_name for f in p["filters"]):
            return PLUGIN_DIR / p["file"]
    raise AssertionError(f"no plugin declares {filter_name}")


def read_off(path):
    """An OFF file of plugin_apply: its floats (nine digits read back exactly) and faces."""
    words = path.read_text().split()
    nv, nf = int(words[1]), int(words[2])
    V = np.array(words[4:4 + 3 * nv], float).astype(np.float32).reshape(-1, 3)
    F = np.array(words[4 + 3 * nv:4 + 3 * nv + 4 * nf], np.int64).reshape(-1, 4)[:, 1:]
    return V, F


def apply(tmp_path, filter_name, meshes, **params):
    """Runs the filter on the meshes (one layer each, the first current):
    (ok, error, log, [(label, V, F) per layer after the filter])."""
    inputs = [robustness_shapes.write_off(tmp_path / f"in{i}.off", V, F) for i, (V, F) in enumerate(meshes)]
    out = tmp_path / "out"
    out.mkdir()
    args = [f"{k}={('true' if v else 'false') if isinstance(v, bool) else v}" for k, v in params.items()]
    proc = subprocess.run([str(BUILD / "tests" / "plugin_apply"), str(plugin_of(filter_name)), filter_name,
                           str(out), *map(str, inputs), "--", *args],
                          capture_output=True, text=True, timeout=SECONDS * 3)
    assert proc.returncode == 0, proc.stderr[-3000:]
    r = json.loads(proc.stdout)
    layers = [(l["label"], *read_off(ROOT / l["file"])) for l in r["layers"]]
    return r["ok"], r["error"], "\n".join(r["log"]), layers


def assert_layer_as_given(layer, mesh):
    """The layer holds the mesh exactly as MeshLab stored it (float)."""
    _, V, F = layer
    np.testing.assert_array_equal(V, np.asarray(mesh[0], float).astype(np.float32))
    np.testing.assert_array_equal(F, np.asarray(mesh[1]))


# ---- refusals: a precondition, a work bound, a contract -----------------------------

def test_precondition_refusal_names_a_meshmend_remedy_and_changes_nothing(tmp_path):
    mesh = CLASSES["inconsistently_oriented"]
    ok, error, log, layers = apply(tmp_path, REMOVE, [mesh])
    assert not ok
    assert "not consistently oriented" in error and "MeshMend: Close Gaps Between Borders" in error
    assert len(layers) == 1
    assert_layer_as_given(layers[0], mesh)


def test_work_bound_refusal_on_the_spindle_torus_is_quick_and_changes_nothing(tmp_path):
    mesh = CLASSES["spindle_torus"]
    ok, error, _, layers = apply(tmp_path, REMOVE, [mesh])
    assert not ok
    assert "max_triple_points_per_face" in error and "Nothing was changed" in error
    assert len(layers) == 1
    assert_layer_as_given(layers[0], mesh)


def test_pair_bound_refusal_changes_nothing(tmp_path):
    mesh = CLASSES["openscad_export"]
    ok, error, _, layers = apply(tmp_path, REMOVE, [mesh], max_intersecting_pairs=5)
    assert not ok
    assert "max_intersecting_pairs" in error
    assert_layer_as_given(layers[0], mesh)


@pytest.mark.parametrize("name", list(CLASSES))
def test_removal_on_every_class_is_valid_or_leaves_the_layer_unchanged(tmp_path, name):
    """Each generated class: either a result that meets the contract (checked
    here again on what the layer holds) or a refusal with the layer as it was."""
    mesh = CLASSES[name]
    ok, error, log, layers = apply(tmp_path, REMOVE, [mesh])
    assert len(layers) == 1
    if not ok:
        print(f"{name}: refused: {error[:160]}")
        assert error and "internal error" not in error
        assert_layer_as_given(layers[0], mesh)
        return
    print(f"{name}: valid")
    label, V, F = layers[0]
    assert not label.endswith("(partial)")
    assert len(F) > 0
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert uses.max() <= 2  # edge-manifold
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    _, runs = np.unique(directed, axis=0, return_counts=True)
    assert runs.max() == 1  # no edge run the same way by two faces


def test_a_partial_result_is_written_only_when_asked_and_marked(tmp_path):
    """A result that misses the contract: refused by default, the layer as
    it was; with keep_partial written, its label ending in '(partial)'."""
    V, F = cube()
    # Two cubes sharing an edge, left touching (no separation): the contract
    # (no intersecting pair) cannot hold.
    V2 = np.vstack([V, np.asarray(V, float) + (1, 1, 0)])
    F2 = np.vstack([F, np.asarray(F) + 8])
    mesh = (V2, F2)
    (tmp_path / "refused").mkdir()
    ok, error, _, layers = apply(tmp_path / "refused", REMOVE, [mesh], separate_touching=False)
    assert not ok and "could not make a valid surface" in error and "Nothing was changed" in error
    assert_layer_as_given(layers[0], mesh)
    (tmp_path / "kept").mkdir()
    ok, _, log, layers = apply(tmp_path / "kept", REMOVE, [mesh], separate_touching=False,
                               keep_partial=True)
    assert ok
    assert layers[0][0].endswith("(partial)") and "PARTIAL result" in log


# ---- nothing to do is success --------------------------------------------------------

@pytest.mark.parametrize("filter_name", [REMOVE, SPLIT, FILL, CLOSE])
def test_nothing_to_do_is_success_and_changes_nothing(tmp_path, filter_name):
    """A closed cube that does not intersect itself: nothing to remove, to
    split (within the current layer: the split self-intersections sample),
    to fill or to close."""
    mesh = cube()
    ok, error, log, layers = apply(tmp_path, filter_name, [mesh])
    assert ok, error
    assert "unchanged" in log or "nothing to do" in log, log
    assert len(layers) == 1
    assert_layer_as_given(layers[0], mesh)


def test_split_of_layers_that_do_not_meet_is_success_and_changes_nothing(tmp_path):
    a = cube()
    b = (np.asarray(a[0], float) + 5, a[1])
    ok, error, log, layers = apply(tmp_path, SPLIT, [a, b], mode=1, first_layer=0, second_layer=1,
                                   output=0)
    assert ok, error
    assert "do not intersect" in log
    assert len(layers) == 2
    assert_layer_as_given(layers[0], a)
    assert_layer_as_given(layers[1], b)
