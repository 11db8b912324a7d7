"""MeshMend in the MeshLab 2025.07 GUI, its float and its double build (made
by scripts/hosts), under Xvfb as a user runs it: the GUI loads every
MeshMend plugin and its filter search lists every MeshMend filter (read back
from the screen), Fill Holes is applied from its dialog (the report file
typed into the dialog says the hole was filled), and MeshMend's shaders
compile in 2025.07's render plugin and draw the new faces orange."""
import json
import re
import time

import pytest

from conftest import Host, cube, filters, write_off
from gui_driver import SEARCH, Dialog, MeshLabGui
from test_shaders import orange, view_pixels

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module", params=["2025.07", "2025.07d"])
def host(request):
    h = Host(request.param)
    h.require_gui()
    return h


def open_cube(tmp_path):
    """A unit cube without one of the triangles that face the viewer."""
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


def test_fill_holes_from_its_dialog_and_the_new_faces_shader(host, tmp_path):
    with MeshLabGui(tmp_path, [open_cube(tmp_path)], host=host) as gui:
        dialog = Dialog(gui, "MeshMend: Fill Holes (Feature Preserving)")
        dialog.set("max_diameter", 0)
        dialog.set("report_file", "holes.json")  # relative: MeshLab's working folder
        dialog.apply()
        dialog.close()
        report = json.loads((tmp_path / "holes.json").read_text())
        assert report["holes_filled"] == 1 and report["faces_added"] >= 1, report
        assert report["remaining_intersecting_pairs"] == 0

        dialog = Dialog(gui, "MeshMend: Prepare Shader View")
        dialog.set("values", 2)  # new faces
        dialog.apply()
        dialog.close()
        compiled, log = gui.apply_shader("meshmend_new_faces.gdp")
        assert compiled, f"meshmend_new_faces.gdp does not compile in MeshLab {host.name}: {log}"
        for window in gui.windows("^Form$"):
            gui.xdotool("windowmove", window, 870, 600)
        shot = gui.screenshot(tmp_path / "new_faces.png")
        assert orange(view_pixels(shot)).sum() > 500, "the new face is not drawn orange"
