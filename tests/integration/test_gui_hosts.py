"""MeshMend in the MeshLab 2025.07 GUI, its float and its double build (made
by scripts/hosts), under Xvfb as a user runs it: the GUI loads every
MeshMend plugin and its filter search lists every MeshMend filter (read back
from the screen); every MeshMend filter runs in the GUI (Filters > Show
current filter script, the script opened and applied) with the report
counts of the same script run by meshlabserver on MeshLab 2020.09; Inspect
is applied from its dialog (the report file typed into the dialog); and
MeshMend's shaders compile in 2025.07's render plugin and draw the faces
Fill Holes made orange."""
import json
import re
import time

import pytest

from conftest import DATA, Host, cube, filters, float_exact, mlx, require_shared_data, run_server, write_off, write_ply
from gui_driver import SEARCH, Dialog, MeshLabGui
from test_clearance import nested_spheres
from test_pymeshlab import NAMES, counts
from test_shaders import orange, view_pixels
from test_stitch import indices, joined, sphere, two_sheets

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module", params=["2025.07", "2025.07d"])
def host(request):
    h = Host(request.param)
    h.require_gui()
    return h


def open_cube(tmp_path):
    """A unit cube without one of its triangles."""
    V, F = cube()
    return write_off(tmp_path / "open.off", V, F[:2] + F[3:])


def test_every_plugin_is_loaded_and_every_filter_listed(host, tmp_path):
    with MeshLabGui(tmp_path, [open_cube(tmp_path)], host=host) as gui:
        maps = (open(f"/proc/{gui.meshlab.pid}/maps").read())
        loaded = set(re.findall(r"[^/\s]*mend_[^/\s]*\.so", maps))
        assert {p.name for p in host.plugins} <= loaded, loaded
        gui.click(*SEARCH)
        gui.type("MeshMend")
        time.sleep(1.5)
        # OCR reads the names' words; the colon after "MeshMend" it may drop.
        listed = re.sub(r"\s+", " ", gui.text(gui.screenshot(tmp_path / "search.png"))).replace(":", "")
        for name in filters():
            assert name.replace(":", "") in listed, \
                f"'{name}' not in the filter search of MeshLab {host.name}: {listed[:600]}"
        assert "MeshLab " + host.name in gui.xdotool("getwindowname", gui.window)


def sessions(tmp_path):
    """Each GUI session: its input meshes and the filter steps (python
    name, parameters) run on them; together they run every MeshMend filter."""
    require_shared_data()
    V, F, ring = sphere(8, 12)
    ball = write_off(tmp_path / "sphere.off", V, F)
    A, B, pa, pb = two_sheets(7, 11)
    sheets = write_off(tmp_path / "sheets.off", *joined(A, B))
    shell = write_ply(tmp_path / "shell.ply", *nested_spheres())
    return {
        "pair": ([DATA / "pairs/ballA.off", DATA / "pairs/ballB.off"], [
            ("meshmend_select_intersecting_faces", {"mode": 1, "first_layer": 0, "second_layer": 1}),
            ("meshmend_intersect_and_split", {"mode": 1, "first_layer": 0, "second_layer": 1, "output": 1}),
            ("meshmend_paint_patches", {}),
            ("meshmend_select_patches", {"by": 5}),
            ("meshmend_remove_patches", {"keep": 0, "removed_to_layer": True}),
            ("meshmend_inspect_defects", {"select_defects": 3})]),
        "cow": ([DATA / "self_intersecting/cow.off"], [("meshmend_remove_self_intersections", {})]),
        "shark": ([float_exact(DATA / "holes/mech-holes-shark.off", tmp_path / "shark.off")], [
            ("meshmend_fill_holes", {}), ("meshmend_prepare_shader_view", {"values": 2})]),
        "shell": ([shell], [("meshmend_measure_clearance", {"tau": 0.06}),
                            ("meshmend_enforce_minimum_clearance", {"tau": 0.06}),
                            ("meshmend_measure_clearance", {"tau": 0.06})]),
        "trim": ([ball], [("meshmend_trim_along_vertex_loop", {
            "loop_vertices": indices(ring(4, j) for j in range(12)), "keep_side": 1, "keep_face": len(F) - 1})]),
        "stitch": ([sheets], [("meshmend_stitch_boundaries", {
            "path_a": indices(pa), "path_b": indices(p + len(A[0]) for p in pb)})]),
        "gaps": ([DATA / "stitching/quads_to_stitch.off"], [("meshmend_close_gaps", {})]),
    }


def test_every_filter_runs_in_the_gui_with_the_counts_of_2020_09(host, tmp_path):
    ran = set()
    for name, (inputs, steps) in sessions(tmp_path).items():
        work = tmp_path / name
        work.mkdir()
        script = mlx(*[(NAMES[f], {**values, "report_file": "{report%d}" % k})
                       for k, (f, values) in enumerate(steps)])
        server = run_server(work, inputs, script)
        assert server.returncode == 0, server.log[-3000:]
        ours = [json.loads((work / f"report{k}.json").read_text()) for k in range(len(steps))]
        gui_reports = [work / f"gui{k}.json" for k in range(len(steps))]
        for k, path in enumerate(gui_reports):
            script = script.replace("{report%d}" % k, str(path))
        (work / "gui").mkdir()
        (work / "gui" / "all.mlx").write_text(script)  # MeshLab's working folder: its file dialog opens there
        with MeshLabGui(work / "gui", inputs, host=host) as gui:
            if name == "shark":  # a filter from its dialog, as a user applies one
                dialog = Dialog(gui, "MeshMend: Inspect Mesh Defects")
                dialog.set("report_file", "inspect.json")  # relative: MeshLab's working folder
                dialog.apply()
                dialog.close()
                inspected = json.loads((work / "gui" / "inspect.json").read_text())
                assert inspected["border_loops"] == 4 and inspected["faces"] == 10192, inspected
            gui.run_script(work / "gui" / "all.mlx", gui_reports)
            if name == "shark":  # the new faces of Fill Holes, through MeshMend's shader
                compiled, log = gui.apply_shader("meshmend_new_faces.gdp")
                assert compiled, f"meshmend_new_faces.gdp does not compile in MeshLab {host.name}: {log}"
                for window in gui.windows("^Form$"):
                    gui.xdotool("windowmove", window, 870, 600)
                shot = gui.screenshot(work / "new_faces.png")
                assert orange(view_pixels(shot)).sum() > 500, "the new faces are not drawn orange"
        for k, (f, _) in enumerate(steps):
            theirs = json.loads(gui_reports[k].read_text())
            a, b = counts(ours[k]), counts(theirs)
            if host.double:  # the double build stores double: nothing is rounded to float
                for key in ("host_scalar", "rounded_to_float", "closest", "shortest",
                            "pairs_split_after_rounding"):
                    a.pop(key, None), b.pop(key, None)
                if f == "meshmend_fill_holes":
                    # Patches decided on the stored coordinates may take a few
                    # different refinement steps: each hole within 2 %.
                    holes_a, holes_b = a.pop("holes"), b.pop("holes")
                    assert len(holes_a) == len(holes_b), (name, f)
                    for x, y in zip([a] + holes_a, [b] + holes_b):
                        for key in ("faces_added", "vertices_added"):
                            old, new = x.pop(key), y.pop(key)
                            assert abs(old - new) <= 0.02 * old, (name, f, key, old, new)
                    assert holes_a == holes_b, (name, f)
                if f == "meshmend_prepare_shader_view" and "new_faces" in a:
                    # The same patches, counted after Fill Holes: within 2 % of the new faces.
                    bound = 0.02 * a["new_faces"]
                    for key in ("faces", "new_faces"):
                        old, new = a.pop(key), b.pop(key)
                        assert abs(old - new) <= bound, (name, f, key, old, new)
            assert a == b, (name, f, {key: (a.get(key), b.get(key)) for key in set(a) | set(b)
                                      if a.get(key) != b.get(key)})
            ran.add(f)
    assert ran == set(NAMES)
