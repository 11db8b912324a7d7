"""MeshMend's shaders (shaders/) in the real MeshLab GUI under Xvfb: each is
listed in Render > Shaders, compiles (MeshLab's render plugin writes
shaders.log and shows an error box when a shader does not) and draws what
it should, read back from a screenshot of the 3D view: the clearance heat
map red below tau and ramp colours above, patch colours, new faces orange,
and grey stripes on a layer without MeshMend values. A shader with a
syntax error, in a prefix of its own, is reported as not compiled."""
import shutil
import subprocess

import numpy as np
import pytest

from conftest import BUILD, ROOT, cube, mlx, write_off
from gui_driver import PREFIX, MeshLabGui
from test_render_script import pixels

pytestmark = pytest.mark.gui

PREPARE = "MeshMend: Prepare Shader View"
SHADERS = ["meshmend_clearance.gdp", "meshmend_patches.gdp", "meshmend_new_faces.gdp"]
ARTIFACTS = BUILD / "test-artifacts" / "shaders"
VIEW = (5, 75, 850, 880)  # the 3D view of a 1280 x 1024 MeshLab window (x0, y0, x1, y1)


def prepared(tmp_path, name, inputs, steps):
    """A PLY whose texture coordinates hold MeshMend's values (meshlabserver)."""
    script = tmp_path / f"{name}.mlx"
    script.write_text(mlx(*steps))
    out = tmp_path / f"{name}.ply"
    cmd = [str(ROOT / "scripts" / "meshlabserver")]
    for i in inputs:
        cmd += ["-i", str(i)]
    proc = subprocess.run(cmd + ["-s", str(script), "-o", str(out), "-m", "wt"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:]
    return out


def view_pixels(png):
    x0, y0, x1, y1 = VIEW
    return pixels(png)[y0:y1, x0:x1].astype(int)


def red(img):
    return (img[..., 0] > 150) & (img[..., 1] < 80) & (img[..., 2] < 80)


def orange(img):
    return (img[..., 0] > 150) & (img[..., 1] > 60) & (img[..., 1] < 160) & (img[..., 2] < 60)


def grey(img):
    spread = img.max(axis=2) - img.min(axis=2)
    return (spread < 12) & (img[..., 0] > 60) & (img[..., 0] < 200)


def hues(img):
    """30-degree hue bins that hold at least 300 saturated pixels, the blue
    of MeshLab's background (210-270 degrees) left out."""
    rgb = img / 255.0
    mx, mn = rgb.max(axis=2), rgb.min(axis=2)
    saturated = (mx - mn) > 0.25
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    d = np.where(mx - mn == 0, 1, mx - mn)
    h = np.where(mx == r, (g - b) / d % 6, np.where(mx == g, (b - r) / d + 2, (r - g) / d + 4)) * 60
    bins = np.bincount((h[saturated] // 30).astype(int), minlength=12)
    return {30 * i for i in range(12) if bins[i] >= 300 and not 210 <= 30 * i < 270}


def show(tmp_path, mesh, gdp, name):
    """Opens the mesh in the GUI, applies the shader, moves its dialog off
    the view; returns (compiled, shaders.log text, screenshot)."""
    with MeshLabGui(tmp_path / name, [mesh]) as gui:
        compiled, log = gui.apply_shader(gdp)
        for dialog in gui.windows("^Form$"):
            gui.xdotool("windowmove", dialog, 870, 600)
            gui.xdotool("windowsize", dialog, 400, 300)
        shot = gui.screenshot(ARTIFACTS / f"{name}.png")
        return compiled, log, shot


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("shader_meshes")
    V, F = cube()
    a = write_off(tmp / "a.off", V, F)
    c = write_off(tmp / "c.off", [(x + 0.5, y + 0.5, z + 0.5) for x, y, z in V], F)
    # Two unit cubes 0.005 apart: closer than the dialog's tau (0.01) where they face each other.
    two = write_off(tmp / "two.off", V + [(x + 0.3, y + 0.3, z + 1.005) for x, y, z in V],
                    F + [tuple(i + 8 for i in t) for t in F])
    # One triangle of the z = 1 side (facing the viewer) missing: filled, beside the kept one.
    opened = write_off(tmp / "open.off", V, F[:2] + F[3:])
    paint = (ROOT / "samples" / "paint_patches.mlx").read_text()
    painted = tmp / "painted.mlx"
    painted.write_text(paint.replace("</FilterScript>", "")
                       + mlx((PREPARE, {"values": 1})).split("<FilterScript>")[1])
    patches = tmp / "patches.ply"
    proc = subprocess.run([str(ROOT / "scripts" / "meshlabserver"), "-i", str(a), "-i", str(c),
                           "-s", str(painted), "-o", str(patches), "-m", "wt"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:]
    return {
        "clearance": prepared(tmp, "clearance", [two], [
            ("MeshMend: Measure Clearance", {"tau": 0.02}), (PREPARE, {"values": 0})]),
        "patches": patches,
        "new_faces": prepared(tmp, "new_faces", [opened], [
            ("MeshMend: Fill Holes (Feature Preserving)", {"max_diameter": 0}),
            (PREPARE, {"values": 2})]),
        "plain": write_off(tmp / "plain.off", V, F),
    }


def test_the_shaders_are_installed_beside_the_system_ones():
    folder = PREFIX / "share" / "meshlab" / "shaders"
    for gdp in SHADERS:
        assert (folder / gdp).is_file(), f"{gdp} not in {folder}: run scripts/setup"
    assert (folder / "phong.gdp").exists(), "the system shaders are not linked"
    plugin = PREFIX / "lib" / "x86_64-linux-gnu" / "meshlab" / "plugins" / "librender_gdp.so"
    assert plugin.is_file() and not plugin.is_symlink(), \
        "the prefix should hold the rebuilt render_gdp (shaders/CMakeLists.txt), not Debian's"


def test_clearance_heat_map(tmp_path, meshes):
    compiled, log, shot = show(tmp_path, meshes["clearance"], "meshmend_clearance.gdp", "clearance")
    assert compiled, log
    img = view_pixels(shot)
    assert red(img).sum() > 200  # the faces 0.005 apart, below tau = 0.01
    assert hues(img) - {0, 330}, "no ramp colour above tau"
    assert grey(img).sum() < 2000, "stripes: the values did not reach the shader"


def test_patch_colours(tmp_path, meshes):
    compiled, log, shot = show(tmp_path, meshes["patches"], "meshmend_patches.gdp", "patches")
    assert compiled, log
    assert len(hues(view_pixels(shot))) >= 3


def test_new_faces(tmp_path, meshes):
    compiled, log, shot = show(tmp_path, meshes["new_faces"], "meshmend_new_faces.gdp",
                               "new_faces")
    assert compiled, log
    img = view_pixels(shot)
    assert orange(img).sum() > 200
    assert grey(img).sum() > 200  # the kept faces


def test_a_layer_without_values_shows_stripes(tmp_path, meshes):
    compiled, log, shot = show(tmp_path, meshes["plain"], "meshmend_patches.gdp", "no_values")
    assert compiled, log
    img = view_pixels(shot)
    assert grey(img).sum() > 20000  # the trackball's grey circle alone is a few hundred
    assert not hues(img)


def test_a_shader_that_does_not_compile_is_detected(tmp_path, meshes):
    """A prefix of its own whose patch shader has a syntax error: MeshLab
    says so (error box, shaders.log) and no dialog opens."""
    prefix = tmp_path / "prefix"
    (prefix / "bin").mkdir(parents=True)
    shutil.copy2(PREFIX / "bin" / "meshlab", prefix / "bin" / "meshlab")
    (prefix / "lib").symlink_to(PREFIX / "lib")
    shaders = prefix / "share" / "meshlab" / "shaders"
    shutil.copytree(PREFIX / "share" / "meshlab" / "shaders", shaders, symlinks=True)
    frag = shaders / "meshmend_patches.frag"
    frag.write_text(frag.read_text().replace("float light = lighting();",
                                             "float light = lighting() +;"))
    with MeshLabGui(tmp_path / "broken", [meshes["patches"]], prefix=prefix) as gui:
        compiled, log = gui.apply_shader("meshmend_patches.gdp")
        gui.screenshot(ARTIFACTS / "broken.png")
    assert not compiled
    assert "FRAGMENT SHADER COMPILE INFO" in log and "error" in log.lower(), log
