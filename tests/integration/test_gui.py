"""GUI smoke test: the real MeshLab GUI, under Xvfb, loads every MeshMend
plugin and lists every MeshMend filter (read back from a screenshot of its
filter search with OCR)."""
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import BUILD, PLUGIN_DIR, ROOT, cube, filters, write_off

pytestmark = pytest.mark.gui


def ocr(png, tmp_path):
    big = tmp_path / (png.stem + "_x2.png")
    subprocess.run(["convert", str(png), "-resize", "200%", str(big)], check=True)
    text = subprocess.run(["tesseract", str(big), "-"], capture_output=True, text=True).stdout
    return re.sub(r"\s+", " ", text)


def test_gui_registers_every_meshmend_filter(tmp_path):
    for tool in ("xvfb-run", "xdotool", "import", "tesseract"):
        assert shutil.which(tool), f"{tool} missing: scripts/setup installs it"
    mesh = write_off(tmp_path / "cube.off", *cube())
    out = BUILD / "test-artifacts" / "gui"
    shutil.rmtree(out, ignore_errors=True)
    subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24",
                    str(Path(__file__).with_name("gui_session.sh")), str(out), str(mesh)],
                   timeout=180, check=True)
    assert (out / "alive").exists(), (out / "meshlab.log").read_text()[-2000:]
    loaded = set((out / "plugins.txt").read_text().split())
    built = {p.name for p in PLUGIN_DIR.glob("*.so")}
    assert built and built <= loaded, f"GUI did not load {built - loaded}"
    listed = ocr(out / "search.png", tmp_path)
    for name in filters():
        assert name in listed, f"'{name}' not in the GUI's filter search: {listed[:500]}"
