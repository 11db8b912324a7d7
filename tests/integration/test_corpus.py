"""Counts of the inspect filter, through meshlabserver, equal meshcheck's on
every OFF, PLY and OBJ mesh of ../shared/data (and STL, whose vertices both
unify). Where MeshLab's importer changes the mesh, the report says so and
only the counts the change leaves alone are compared."""
import pytest

from conftest import DATA, ROOT, meshcheck, mlx, require_shared_data, run_server

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
    if keys is KEYS:  # the same triangles: the exact self-intersections agree too
        keys = KEYS + ["self_intersecting_pairs", "self_intersecting_faces"]
    for key in keys:
        assert ours[key] == theirs[key], f"{key}: ours {ours[key]}, meshcheck {theirs[key]}"
    if theirs["volume"] is None or "triangle strips" in notes:
        assert ours["volume"] is None or "triangle strips" in notes
    else:  # MeshLab stores float coordinates; meshcheck reads doubles
        assert ours["volume"] == pytest.approx(theirs["volume"], rel=1e-5)


# ---- exact intersection counts ---------------------------------------------

SELECT = "MeshMend: Select Intersecting Faces"


@pytest.mark.parametrize("name", corpus_files())
def test_self_intersections_match_meshcheck(tmp_path, name):
    require_shared_data()
    path = DATA / name
    run = run_server(tmp_path, [path], mlx((SELECT, {"mode": 0, "report_file": "{report0}"})))
    assert run.returncode == 0, run.log[-2000:]
    ours, theirs = run.report, meshcheck(path)
    if theirs["faces"] == 0 or theirs.get("triangles") != theirs["faces"]:
        pytest.skip(f"{name}: meshcheck sees other faces than MeshLab (strips or polygons)")
    assert ours["self_intersecting_pairs"] == theirs["self_intersecting_pairs"]
    assert ours["self_intersecting_faces"] == theirs["self_intersecting_faces"]


def manifest_pairs():
    """(A, B, cross pairs, faces of A, faces of B) from the MANIFEST's pairs
    table, for the pairs that intersect in the files' own coordinates."""
    if not DATA.is_dir():
        return [("(corpus absent)", "", 0, 0, 0)]
    rows, in_table = [], False
    for line in (DATA / "MANIFEST.md").read_text().splitlines():
        if line.startswith("## "):
            in_table = line.startswith("## Pairs")
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not in_table or len(cells) < 4 or not cells[2].replace(",", "").isdigit():
            continue
        a, b = cells[0].strip("`"), cells[1].strip("`")
        if "(" in b:  # a transformed variant (aligned by a project file)
            continue
        faces = [int(x) for x in cells[3].split("/")]
        rows.append((a, b, int(cells[2].replace(",", "")), faces[0], faces[1]))
    return rows


@pytest.mark.parametrize("a,b,pairs,faces_a,faces_b", manifest_pairs())
def test_cross_intersections_match_the_manifest(tmp_path, a, b, pairs, faces_a, faces_b):
    require_shared_data()
    inputs = []
    for name in (a, b):
        path = DATA / name
        if not path.exists() and (DATA / (name + ".gz")).exists():  # the full dragon ships gzipped
            import gzip
            import shutil
            path = tmp_path / path.name
            with gzip.open(DATA / (name + ".gz"), "rb") as src, open(path, "wb") as dst:
                shutil.copyfileobj(src, dst)
        inputs.append(path)
    script = mlx((SELECT, {"mode": 1, "first_layer": 0, "second_layer": 1, "report_file": "{report0}"}))
    run = run_server(tmp_path, inputs, script)
    assert run.returncode == 0, run.log[-2000:]
    r = run.report
    assert r["cross_intersecting_pairs"] == pairs
    assert r["cross_intersecting_faces_per_layer"] == [faces_a, faces_b]


# ---- intersect and split: clean closed pairs ---------------------------------

SPLIT = "MeshMend: Intersect and Split Layers"


@pytest.mark.parametrize("a,b", [("pairs/blobby.off", "pairs/eight.off"),
                                 ("pairs/cheburashka.off", "pairs/decimated-knight.off"),
                                 ("pairs/cube.obj", "pairs/sphere.obj"),
                                 ("pairs/xcylinder.obj", "pairs/ycylinder.obj"),
                                 ("pairs/ycylinder.obj", "pairs/zcylinder.obj"),
                                 ("pairs/sphere.obj", "pairs/xcylinder.obj"),
                                 ("pairs/ballA.off", "pairs/ballB.off")])
def test_split_of_closed_pairs_leaves_no_intersection(tmp_path, a, b):
    require_shared_data()
    out = tmp_path / "merged.ply"
    script = mlx((SPLIT, {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1,
                          "report_file": "{report0}"}))
    run = run_server(tmp_path, [DATA / a, DATA / b], script, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    r, check = run.report, meshcheck(out)
    assert r["remaining_intersecting_pairs"] == 0
    assert r["open_curves"] == 0 and r["curve_loops"] >= 1
    assert check["self_intersecting_pairs"] == 0 and check["degenerate_faces"] == 0
    assert check["is_closed"] and check["border_edges"] == 0
    assert check["non_manifold_edges"] == r["curve_edges"]


@pytest.mark.parametrize("a,b", [("pairs/blobby.off", "pairs/eight.off"),
                                 ("pairs/cheburashka.off", "pairs/decimated-knight.off"),
                                 ("pairs/sphere.obj", "pairs/xcylinder.obj"),
                                 ("pairs/ballA.off", "pairs/ballB.off"),
                                 ("stanford/bun_zipper_res3.ply", "stanford/dragon_vrip_res3.ply")])
def test_quality_snapping_keeps_the_split_valid(tmp_path, a, b):
    """Snapping removes most slivers (new faces with an angle under 1°) and
    never makes the smallest new angle worse; the written
    result is still free of intersections, closed where the inputs were, with
    the curves as its only new non-manifold edges."""
    require_shared_data()
    out = tmp_path / "merged.ply"
    script = (ROOT / "samples" / "intersect_split.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"').replace(
        'name="snap_tolerance" value="0"', 'name="snap_tolerance" value="0.05"')
    assert 'name="snap_tolerance" value="0.05"' in script
    run = run_server(tmp_path, [DATA / a, DATA / b], script, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    r, check = run.report, meshcheck(out)
    assert r["vertices_snapped"] + r["edges_snapped"] > 0
    assert r["smallest_new_angle_deg"] >= r["smallest_new_angle_deg_unsnapped"]
    assert r["new_faces_below_1deg"] < r["new_faces_below_1deg_unsnapped"] / 2
    assert "without snapping" in run.log
    assert r["remaining_intersecting_pairs"] == 0
    assert check["self_intersecting_pairs"] == 0
    inputs = [meshcheck(DATA / p) for p in (a, b)]
    if all(i["non_manifold_edges"] == 0 for i in inputs):  # (the decimated dragon has 2,094)
        assert check["non_manifold_edges"] == r["curve_edges"]
    assert check["is_closed"] == all(i["is_closed"] for i in inputs)


def test_split_bunny_and_dragon_full_is_free_of_intersections(tmp_path):
    """The paper's benchmark pair, with the dragon's seams welded and its own
    self-intersections split in the same pass (samples/intersect_split.mlx)."""
    require_shared_data()
    import gzip
    import shutil
    dragon = tmp_path / "dragon_vrip.ply"
    with gzip.open(DATA / "stanford" / "dragon_vrip.ply.gz", "rb") as src, open(dragon, "wb") as dst:
        shutil.copyfileobj(src, dst)
    out = tmp_path / "merged.ply"
    script = (ROOT / "samples" / "intersect_split.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"')
    run = run_server(tmp_path, [DATA / "stanford" / "bun_zipper.ply", dragon], script, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    r, check = run.report, meshcheck(out)
    assert r["remaining_intersecting_pairs"] == 0
    assert check["self_intersecting_pairs"] == 0
    assert check["non_manifold_edges"] == r["curve_edges"]
    # Borders only where the bunny had them (its five holes; curve points split a few edges).
    assert check["border_loops"] == 5


@pytest.mark.parametrize("res", [2, 3, 4])
def test_split_decimated_bunny_and_dragon_is_free_of_intersections(tmp_path, res):
    """The decimated pairs have duplicate faces (the same surface twice) and
    non-manifold edges: the sample removes the duplicates and splits the rest."""
    require_shared_data()
    inputs = [DATA / "stanford" / f"bun_zipper_res{res}.ply",
              DATA / "stanford" / f"dragon_vrip_res{res}.ply"]
    duplicates = sum(meshcheck(p)["duplicate_faces"] for p in inputs)
    out = tmp_path / "merged.ply"
    script = (ROOT / "samples" / "intersect_split.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"')
    run = run_server(tmp_path, inputs, script, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    r, check = run.report, meshcheck(out)
    assert duplicates > 0 and r["duplicate_faces_removed"] == duplicates
    assert r["remaining_intersecting_pairs"] == 0
    assert check["self_intersecting_pairs"] == 0
    assert check["duplicate_faces"] == 0


@pytest.mark.parametrize("name", ["self_intersecting/cow.off", "self_intersecting/pig.off",
                                  "self_intersecting/self_intersectA.obj"])
def test_split_along_own_self_intersections(tmp_path, name):
    require_shared_data()
    out = tmp_path / "split.ply"
    script = (ROOT / "samples" / "split_self_intersections.mlx").read_text().replace(
        'name="report_file" value=""', 'name="report_file" value="{report0}"')
    run = run_server(tmp_path, [DATA / name], script, outputs=[out])
    assert run.returncode == 0, run.log[-2000:]
    r, check = run.report, meshcheck(out)
    assert r["remaining_intersecting_pairs"] == 0
    assert check["self_intersecting_pairs"] == 0
    # Every curve edge is non-manifold; welding the cow's duplicate vertex adds one of its own.
    assert r["curve_edges"] <= check["non_manifold_edges"] <= r["curve_edges"] + 1
