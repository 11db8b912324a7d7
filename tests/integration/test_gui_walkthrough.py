"""The GUI as a user meets it: every MeshMend filter opened from MeshLab's
filter search on a real mesh, a parameter's tooltip shown, parameters set
in the dialog, applied with its Apply button, and its shader views drawn.
Each step is checked without reading pixels: the dialog is the filter's
own window, the tooltip's words are on the screen, and the filter wrote
the report file typed into its dialog (so it ran, through the GUI, with
those parameters) with the expected outcome. Screenshots of each dialog
(with its tooltip) and of each result go to
build/test-artifacts/gui-walkthrough; scripts/pictures copies them to
docs/gui."""
import json
import math
import re
import shutil
import time

import numpy as np
import pytest

from conftest import BUILD, DATA, filters, require_shared_data, write_off
from gui_driver import SCREEN, Dialog, MeshLabGui

pytestmark = pytest.mark.gui

SHOTS = BUILD / "test-artifacts" / "gui-walkthrough"


@pytest.fixture(scope="module", autouse=True)
def fresh_screenshots():
    require_shared_data()
    shutil.rmtree(SHOTS, ignore_errors=True)
    SHOTS.mkdir(parents=True)


def slug(name):
    return re.sub(r"[^a-z0-9]+", "_", name.replace("MeshMend: ", "").lower()).strip("_")


def run_filter(gui, name, values, hover, check):
    """The whole walk for one filter; `check(report)` asserts its outcome in
    the report it wrote to the file typed into its dialog."""
    dialog = Dialog(gui, name)
    path = gui.workdir / f"{slug(name)}.json"
    for key, value in values.items():
        dialog.set(key, value)
    dialog.set("report_file", path.name)  # relative: MeshLab's working folder
    seen, tooltip = dialog.tooltip(hover, SHOTS / f"{slug(name)}_dialog.png")
    # Its first words, read back from the screen (OCR misses a few on the yellow tooltip).
    tip = re.findall(r"[A-Za-z]{4,}", tooltip)[:8]
    found = sum(1 for w in tip if w.lower() in seen.lower())
    assert found >= min(4, len(tip)), f"tooltip of {hover!r} not on screen: {tip} in {seen[-600:]}"
    log = dialog.apply()
    dialog.close()
    gui.screenshot(SHOTS / f"{slug(name)}_applied.png")
    assert path.exists(), f"{name} wrote no report to {path.name}: " + "\n".join(log[-20:])
    check(json.loads(path.read_text()))


def show_shader(gui, gdp, shot, uniforms=()):
    compiled, log = gui.apply_shader(gdp)
    assert compiled, log
    form = gui.windows("^Form$")[0]
    for name, values in uniforms:
        label = gui.find(name, timeout=3)
        assert label, f"no uniform {name} in the shader dialog"
        for k, v in enumerate(values):
            shape = gui.xdotool("getwindowgeometry", form)
            w, _ = map(int, re.search(r"Geometry: (\d+)x(\d+)", shape).groups())
            # One line edit per component, in the columns right of the label.
            gui.click(label.left + 150 + k * (w - 170) // len(values) + 20, label.center[1])
            gui.key("ctrl+a")
            gui.type(f"{v:g}")
            gui.key("Tab")
    gui.xdotool("windowmove", form, 870, 600)
    gui.xdotool("windowsize", form, 400, 300)
    time.sleep(1.5)
    gui.screenshot(SHOTS / shot)
    # Back to MeshLab's own drawing (selections show again) for the next filters.
    gui.open_menu("Render", "Shaders", "None")
    for window in gui.windows("^Form$"):
        gui.xdotool("windowunmap", window, check=False)
    time.sleep(1)


# ---- the sessions ------------------------------------------------------------------

def test_self_intersections_on_the_cow(tmp_path):
    cow = DATA / "self_intersecting" / "cow.off"
    with MeshLabGui(tmp_path, [cow]) as gui:
        run_filter(gui, "MeshMend: Inspect Mesh Defects", {"select_defects": 6},
                   "self_intersections",
                   lambda r: r["self_intersecting_pairs"] == 118 or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Select Intersecting Faces", {}, "segments_layer",
                   lambda r: r["self_intersecting_pairs"] == 118 or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Remove Self-Intersections", {}, "separate_touching",
                   lambda r: r["remaining_intersecting_pairs"] == 0 or pytest.fail(str(r)))


def test_intersect_paint_and_remove_patches(tmp_path):
    pair = [DATA / "pairs" / "blobby.off", DATA / "pairs" / "eight.off"]
    with MeshLabGui(tmp_path, pair) as gui:
        run_filter(gui, "MeshMend: Intersect and Split Layers", {"mode": 1, "output": 1},
                   "split_self_intersections",
                   lambda r: (r["curve_edges"] == 303 and r["remaining_intersecting_pairs"] == 0)
                   or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Paint Surface Patches", {}, "classify",
                   lambda r: r["patches"] >= 4 or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Prepare Shader View", {"values": 1}, "report_file",
                   lambda r: r["values"] == "patches" or pytest.fail(str(r)))
        show_shader(gui, "meshmend_patches.gdp", "shader_patches.png")
        run_filter(gui, "MeshMend: Select Patches", {"by": 2}, "ids",
                   lambda r: r["patches_selected"] > 0 or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Remove Patches", {"keep": 1}, "removed_to_layer",
                   lambda r: (r["border_edges"] == 0 and r["remaining_intersecting_pairs"] == 0)
                   or pytest.fail(str(r)))


def test_fill_holes_and_the_new_faces_shader(tmp_path):
    with MeshLabGui(tmp_path, [DATA / "holes" / "mech-holes-shark.off"]) as gui:
        run_filter(gui, "MeshMend: Fill Holes (Feature Preserving)", {}, "max_diameter",
                   lambda r: (r["holes_filled"] == 4 and r["faces_added"] > 0)
                   or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Prepare Shader View", {"values": 2}, "report_file",
                   lambda r: r["new_faces"] > 0 or pytest.fail(str(r)))
        show_shader(gui, "meshmend_new_faces.gdp", "shader_new_faces.png")


def quantised_spot(tmp_path):
    """spot.obj with its coordinates rounded to 9 bits of its diagonal."""
    V, F = [], []
    for line in open(DATA / "scanned" / "spot.obj"):
        w = line.split()
        if w and w[0] == "v":
            V.append([float(x) for x in w[1:4]])
        elif w and w[0] == "f":
            F.append(tuple(int(p.split("/")[0]) - 1 for p in w[1:4]))
    P = np.array(V)
    step = np.linalg.norm(P.max(0) - P.min(0)) / 512
    return write_off(tmp_path / "spot_quantised.off", [tuple(q) for q in np.round(P / step) * step], F)


def test_clearance_on_a_quantised_scan(tmp_path):
    tau = 0.006
    with MeshLabGui(tmp_path, [quantised_spot(tmp_path)]) as gui:
        run_filter(gui, "MeshMend: Measure Clearance", {"tau": tau}, "tau",
                   lambda r: r["violating_pairs"] > 0 or pytest.fail(str(r)))
        run_filter(gui, "MeshMend: Prepare Shader View", {"values": 0}, "report_file",
                   lambda r: r["values"] == "clearance" or pytest.fail(str(r)))
        show_shader(gui, "meshmend_clearance.gdp", "shader_clearance.png",
                    [("tau", [tau]), ("colour_range", [tau, 2 * tau])])  # measured up to 2 tau
        run_filter(gui, "MeshMend: Enforce Minimum Clearance", {"tau": tau}, "max_displacement",
                   lambda r: (r["reached"] and r["min_distance_after"] >= tau)
                   or pytest.fail(str(r)))


def horn_loop(V, F):
    """The border of the faces near the highest vertex (the tip of one of
    spot's horns), as a closed loop of vertex indices, and a face outside it."""
    P = np.array(V)
    tip = P[P[:, 1].argmax()]
    inside = [f for f, t in enumerate(F) if np.linalg.norm(P[list(t)].mean(0) - tip) < 0.15]
    uses = {}
    for f in inside:
        t = F[f]
        for k in range(3):
            uses.setdefault(frozenset((t[k], t[(k + 1) % 3])), []).append((t[k], t[(k + 1) % 3]))
    border = [e[0] for e in uses.values() if len(e) == 1]
    following = dict(border)
    start = border[0][0]
    loop = [start]
    while following[loop[-1]] != start:
        loop.append(following[loop[-1]])
    assert len(loop) == len(border), "the top faces do not form one disk"
    outside = next(f for f in range(len(F)) if f not in set(inside))
    return loop, outside, len(inside)


def test_trim_a_horn_along_a_vertex_loop(tmp_path):
    spot = quantised_spot(tmp_path)
    lines = spot.read_text().split("\n")
    nv, nf = map(int, lines[1].split()[:2])
    V = [tuple(map(float, l.split())) for l in lines[2:2 + nv]]
    F = [tuple(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]]
    loop, keep, removed = horn_loop(V, F)
    with MeshLabGui(tmp_path, [spot]) as gui:
        run_filter(gui, "MeshMend: Trim Along Vertex Loop",
                   {"loop_vertices": " ".join(map(str, loop)), "keep_side": 1, "keep_face": keep},
                   "loop_vertices",
                   lambda r: (r["faces_removed"] == removed and r["border_edges_after"] == len(loop))
                   or pytest.fail(str(r)))


def stl_soup(path, out):
    """An STL's facets as an OFF soup (MeshLab's STL importer would weld them)."""
    import struct
    data = path.read_bytes()
    count = struct.unpack_from("<I", data, 80)[0]
    assert len(data) == 84 + 50 * count, "binary STL expected"
    facets = [struct.unpack_from("<9f", data, 84 + 50 * i + 12) for i in range(count)]
    V = [f[3 * k:3 * k + 3] for f in facets for k in range(3)]
    return write_off(out, V, [(3 * i, 3 * i + 1, 3 * i + 2) for i in range(count)])


def test_close_gaps_in_an_stl_soup(tmp_path):
    soup = stl_soup(DATA / "stitching" / "busted.STL", tmp_path / "busted_soup.off")
    with MeshLabGui(tmp_path, [soup]) as gui:
        run_filter(gui, "MeshMend: Close Gaps Between Borders", {}, "merge_tolerance",
                   lambda r: (r["border_edges_before"] == 11634 and r["border_edges_after"] == 0)
                   or pytest.fail(str(r)))


def test_stitch_two_sheets_across_a_gap(tmp_path):
    """Two wavy sheets of a 12 x 8 grid, 0.1 apart: their facing borders are
    the paths typed into the dialog."""
    rows, n = 8, 12
    wave = lambda x, y: 0.1 * math.sin(3 * y)

    def sheet(x0, x1):
        V = [(x0 + (x1 - x0) * i / (n - 1), j / (rows - 1)) for i in range(n) for j in range(rows)]
        V = [(x, y, wave(x, y)) for x, y in V]
        F = []
        for i in range(n - 1):
            for j in range(rows - 1):
                a, b = i * rows + j, (i + 1) * rows + j
                F += [(a, b, b + 1), (a, b + 1, a + 1)]
        return V, F
    (Va, Fa), (Vb, Fb) = sheet(0, 1), sheet(1.1, 2.1)
    src = write_off(tmp_path / "sheets.off", Va + Vb, Fa + [tuple(i + len(Va) for i in t) for t in Fb])
    path_a = [(n - 1) * rows + j for j in range(rows)]  # the right border of the first sheet
    path_b = [len(Va) + j for j in range(rows)]  # the left border of the second
    with MeshLabGui(tmp_path, [src]) as gui:
        run_filter(gui, "MeshMend: Stitch Boundaries",
                   {"path_a": " ".join(map(str, path_a)), "path_b": " ".join(map(str, path_b))},
                   "path_a",
                   lambda r: r["faces_added"] == 2 * (rows - 1) or pytest.fail(str(r)))


def test_every_filter_has_a_walk():
    """Each MeshMend filter appears in one of the sessions above."""
    source = open(__file__).read()
    for name in filters():
        assert f'"{name}"' in source, f"{name} has no GUI walkthrough"
