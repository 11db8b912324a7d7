"""The end-of-edit contract in the Python module, as in the filters: a
result of stitch_boundaries, stitch_sequence, close_gaps or
enforce_clearance that misses it raises meshmend.Error ("... Nothing was
changed. ...") and returns nothing, the input arrays as they were; with
keep_partial=True it is returned, its report saying contract_met False,
partial True and what failed (the keys of the filters' report_file).

Run from the build:  MESHMEND_BUILD_DIR=build /usr/bin/python3 -m pytest tests/python/test_edit_contract.py
"""
import os
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("MESHMEND_BUILD_DIR", ROOT / "build"))
sys.path.insert(0, str(BUILD / "python"))

import meshmend as mm  # noqa: E402


def sheet(nx, ny, x0=0.0, y0=0.0, z=0.0, cell=0.1):
    """nx by ny squares in the plane at height z from (x0, y0), normals +z.
    Vertex (i, j) is j * (nx + 1) + i."""
    V = [(x0 + i * cell, y0 + j * cell, z) for j in range(ny + 1) for i in range(nx + 1)]
    at = lambda i, j: j * (nx + 1) + i  # noqa: E731
    F = []
    for j in range(ny):
        for i in range(nx):
            F += [(at(i, j), at(i + 1, j), at(i + 1, j + 1)), (at(i, j), at(i + 1, j + 1), at(i, j + 1))]
    return np.array(V, float), np.array(F), at


def joined(*meshes):
    V, F, offset = [], [], 0
    for v, f in meshes:
        V.append(np.asarray(v, float))
        F.append(np.asarray(f) + offset)
        offset += len(v)
    return np.vstack(V), np.vstack(F)


def plate_across(y):
    """A vertical plate in the plane at y, through z = 0 along the sheets'
    borders: whatever spans the gap there passes through it."""
    V = np.array([(-0.1, y, -0.1), (1.1, y, -0.1), (1.1, y, 0.1), (-0.1, y, 0.1)])
    return V, np.array([(0, 1, 2), (0, 2, 3)])


def sheets_with_a_plate_in_the_gap(gap):
    """Two 10 x 5 sheets, their facing borders `gap` apart, a plate in the
    middle of the gap: a stitch across it intersects the plate."""
    Va, Fa, at_a = sheet(10, 5)
    Vb, Fb, at_b = sheet(10, 5, y0=0.5 + gap)
    V, F = joined((Va, Fa), (Vb, Fb), plate_across(0.5 + gap / 2))
    top_a = [at_a(i, 5) for i in range(11)]
    bottom_b = [len(Va) + at_b(i, 0) for i in range(11)]
    return V, F, top_a, bottom_b


def refused(function, inputs, *args, **options):
    """The call raises the contract's error and leaves `inputs` as they were."""
    copies = [np.array(a, copy=True) for a in inputs]
    with pytest.raises(mm.Error, match="could not make a valid result") as caught:
        function(*inputs, *args, **options)
    message = str(caught.value)
    assert "Nothing was changed" in message and "keep_partial=True" in message
    for given, copy in zip(inputs, copies):
        assert np.array_equal(given, copy)
    return message


def assert_partial(report, failure):
    assert report["contract_met"] is False and report["partial"] is True
    assert any(failure in f for f in report["contract_failures"]), report["contract_failures"]


def test_a_stitch_through_the_mesh_is_refused_or_kept_as_partial(tmp_path):
    V, F, a, b = sheets_with_a_plate_in_the_gap(0.1)
    message = refused(mm.stitch_boundaries, (V, F), a, b)
    assert message.startswith("stitch_boundaries could not make a valid result")
    assert "intersecting face pairs" in message
    kept = mm.stitch_boundaries(V, F, a, b, keep_partial=True, report_file=str(tmp_path / "r.json"))
    assert_partial(kept.report, "intersecting face pairs with a new or changed face")
    assert kept.report["changed_faces"] == len(kept.new_faces) == 20
    assert kept.report["new_intersecting_pairs"] > 0 and len(kept.faces) == len(F) + 20
    assert '"partial": true' in (tmp_path / "r.json").read_text()
    # Without the plate, the same stitch meets the contract.
    clear = mm.stitch_boundaries(V, F[:-2], a, b)
    assert clear.report["contract_met"] and not clear.report["partial"]
    assert clear.report["contract_failures"] == [] and clear.report["changed_faces"] == 20


def test_a_sequence_through_the_mesh_is_refused_or_kept_as_partial():
    V, F, a, b = sheets_with_a_plate_in_the_gap(0.1)
    message = refused(mm.stitch_sequence, (V, F), [a, b])
    assert message.startswith("stitch_sequence could not make a valid result")
    kept = mm.stitch_sequence(V, F, [a, b], keep_partial=True)
    assert_partial(kept.report, "intersecting face pairs")
    assert len(kept.faces) == len(F) + kept.report["faces_added"] > len(F)
    assert mm.stitch_sequence(V, F[:-2], [a, b]).report["contract_met"]


def test_closing_a_slit_through_the_mesh_is_refused_or_kept_as_partial():
    V, F, _, _ = sheets_with_a_plate_in_the_gap(0.01)
    options = dict(max_gap=0.02, absolute_distances=True, local_gap_factor=0)
    # Checked per stitch (the default), the stitch through the plate is left out.
    checked = mm.close_gaps(V, F, **options)
    assert checked.report["gaps_stitched"] == 0 and checked.report["contract_met"]
    # Unchecked, it is made, and the contract does not hold.
    message = refused(mm.close_gaps, (V, F), check_intersections=False, **options)
    assert message.startswith("close_gaps could not make a valid result")
    kept = mm.close_gaps(V, F, check_intersections=False, keep_partial=True, **options)
    assert_partial(kept.report, "intersecting face pairs")
    assert kept.report["faces_added"] > 0 and kept.report["changed_faces"] > 0
    # Nothing to merge or stitch: met, unchecked.
    nothing = mm.close_gaps(V, F, max_gap=0).report
    assert nothing["contract_met"] and nothing["changed_faces"] == 0


def three_plates():
    """A coarse plate (2 faces) at z = 0 and a fine one (128 faces) at
    z = 0.3, both locked, and a plate at z = 0.15 between them: a tau of
    0.25 cannot hold on both sides, and the many pairs with the fine plate
    push the middle one towards the coarse plate, closer than any pair was."""
    Vc, Fc, _ = sheet(1, 1, cell=1.0)
    Vf, Ff, _ = sheet(8, 8, z=0.3, cell=0.125)
    locked_mesh = joined((Vc, Fc), (Vf, Ff))
    middle = sheet(1, 1, x0=0.1, y0=0.1, z=0.15, cell=0.8)[:2]
    return locked_mesh, middle


def test_a_clearance_that_brings_a_pair_closer_is_refused_or_kept_as_partial():
    (V1, F1), (V2, F2) = three_plates()
    options = dict(tau=0.25, scope="between_layers", locked=[np.ones(len(V1), bool), None])
    message = refused(mm.enforce_clearance, (V1, F1, V2, F2), **options)
    assert message.startswith("enforce_clearance could not make a valid result")
    assert "the smallest distance fell from 0.150000" in message
    kept = mm.enforce_clearance(V1, F1, V2, F2, keep_partial=True, **options)
    r = kept.report
    assert_partial(r, "the smallest distance fell")
    assert r["min_distance_after"] < r["min_distance_before"] == pytest.approx(0.15)
    assert not r["unchanged"] and not r["reached"]
    assert np.array_equal(kept.meshes[0][0], V1)  # locked
    # A tau both sides allow: met.
    met = mm.enforce_clearance(V1, F1, V2, F2, **dict(options, tau=0.14)).report
    assert met["contract_met"] and not met["partial"] and met["contract_failures"] == []


def test_trimming_reports_its_contract():
    V, F, at = sheet(4, 4)
    loop = [at(1, 1), at(2, 1), at(3, 1), at(3, 2), at(3, 3), at(2, 3), at(1, 3), at(1, 2)]
    r = mm.trim_along_loop(V, F, loop=loop, keep_face=0).report
    assert r["contract_met"] and not r["partial"] and r["contract_failures"] == []
    assert r["changed_faces"] == 0
