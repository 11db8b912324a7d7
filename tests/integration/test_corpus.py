"""Counts of the inspect filter, through meshlabserver, equal meshcheck's on
every OFF, PLY and OBJ mesh of ../shared/data (and STL, whose vertices both
unify). Where MeshLab's importer changes the mesh, the report says so and
only the counts the change leaves alone are compared."""
import pytest

from conftest import DATA, meshcheck, mlx, require_shared_data, run_server

pytestmark = pytest.mark.corpus

KEYS = ["vertices", "faces", "edges", "connected_components", "border_edges", "border_loops",
        "longest_border_loop", "non_manifold_edges", "non_manifold_vertices", "degenerate_faces",
        "duplicate_faces", "isolated_vertices", "duplicate_points", "is_closed",
        "consistently_oriented", "orientation_inconsistent_edges"]


def corpus_files():
    if not DATA.is_dir():
        return ["(corpus absent)"]
    exts = {".off", ".ply", ".obj", ".stl"}
    return sorted(str(p.relative_to(DATA)) for p in DATA.rglob("*") if p.suffix.lower() in exts)


@pytest.mark.parametrize("name", corpus_files())
def test_inspect_matches_meshcheck(tmp_path, name):
    require_shared_data()
    path = DATA / name
    run = run_server(tmp_path, [path], mlx(("MeshMend: Inspect Mesh Defects", {"report_file": "{report0}"})))
    assert run.returncode == 0, run.log[-2000:]
    ours, theirs = run.report, meshcheck(path)
    notes = " ".join(ours["importer_notes"])
    keys = KEYS
    if "triangle strips" in notes:
        assert theirs["faces"] == 0  # meshcheck cannot read strips
        keys = ["vertices"]
    elif "triangulated" in notes:  # polygons became triangles: face and edge counts differ
        keys = [k for k in KEYS if k not in ("faces", "edges")]
        assert ours["faces"] > theirs["faces"]
    for key in keys:
        assert ours[key] == theirs[key], f"{key}: ours {ours[key]}, meshcheck {theirs[key]}"
    if theirs["volume"] is None or "triangle strips" in notes:
        assert ours["volume"] is None or "triangle strips" in notes
    else:  # MeshLab stores float coordinates; meshcheck reads doubles
        assert ours["volume"] == pytest.approx(theirs["volume"], rel=1e-5)
