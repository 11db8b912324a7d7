"""scripts/render (tools/meshmend_render + ImageMagick): pictures of small
meshes made here, read back pixel by pixel: the PNG exists, has the asked
size, shows the mesh, and colours what each mode says (red where faces
intersect or come closer than tau, orange where faces are new), also for a
MeshLab project whose matrices place the layers; bad input gets a message."""
import subprocess

import numpy as np
import pytest

from conftest import ROOT, cube, write_off

RENDER = ROOT / "scripts" / "render"


def render(tmp_path, *args, name="out.png"):
    out = tmp_path / name
    proc = subprocess.run([str(RENDER), *map(str, args), "-o", str(out)], capture_output=True,
                          text=True, timeout=300)
    return proc, out


def pixels(png):
    """The picture as an H x W x 3 array (through ImageMagick's PPM)."""
    data = subprocess.run(["convert", str(png), "-depth", "8", "ppm:-"], capture_output=True,
                          check=True).stdout
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maximum
        while data[pos:pos + 1].isspace():
            pos += 1
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    assert fields[0] == b"P6" and fields[3] == b"255"
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(data[pos + 1:pos + 1 + w * h * 3], np.uint8).reshape(h, w, 3)


def red(img):
    r, g, b = (img[..., k].astype(int) for k in range(3))
    return (r > 150) & (g < 80) & (b < 80)


def orange(img):
    r, g, b = (img[..., k].astype(int) for k in range(3))
    return (r > 150) & (g > 60) & (g < 160) & (b < 60)


def moved(V, d):
    return [(x + d[0], y + d[1], z + d[2]) for x, y, z in V]


def test_a_cube_becomes_a_picture_of_the_asked_size(tmp_path):
    src = write_off(tmp_path / "cube.off", *cube())
    proc, out = render(tmp_path, src, "--size", "320,240")
    assert proc.returncode == 0, proc.stderr
    img = pixels(out)
    assert img.shape == (240, 320, 3)
    covered = (img < 250).any(axis=2)  # not the white background
    assert 0.2 < covered.mean() < 0.9, covered.mean()
    # Three faces of the cube face the viewer, each with its own shade.
    shades = {tuple(int(c) // 8 for c in p) for p in img[covered]}
    assert len(shades) >= 3
    assert not red(img).any()


def test_intersecting_faces_are_red_only_where_they_cross(tmp_path):
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    crossing = write_off(tmp_path / "b.off", moved(V, (0.5, 0.5, 0.5)), F)
    apart = write_off(tmp_path / "c.off", moved(V, (3, 0, 0)), F)
    proc, out = render(tmp_path, "--colour", "intersecting", a, crossing, name="x.png")
    assert proc.returncode == 0, proc.stderr
    assert "intersecting pairs" in proc.stderr
    assert red(pixels(out)).sum() > 100
    proc, out = render(tmp_path, "--colour", "intersecting", a, apart, name="y.png")
    assert proc.returncode == 0, proc.stderr
    assert "0 intersecting pairs" in proc.stderr
    assert not red(pixels(out)).any()


def project(path, layers):
    """A MeshLab project: (file name, 4 x 4 row-major matrix) per layer."""
    body = "".join(
        f'  <MLMesh label="{name}" filename="{name}">\n   <MLMatrix44>\n'
        + "".join(" ".join(map(str, matrix[4 * r:4 * r + 4])) + "\n" for r in range(4))
        + "</MLMatrix44>\n  </MLMesh>\n" for name, matrix in layers)
    path.write_text("<!DOCTYPE MeshLabDocument>\n<MeshLabProject>\n <MeshGroup>\n" + body
                    + " </MeshGroup>\n</MeshLabProject>\n")
    return path


IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]


def test_a_project_places_its_layers_by_their_matrices(tmp_path):
    """A cube and a copy 5 units away: the project's matrix moves the copy
    into the cube (they intersect: red); with the identity they stay apart."""
    write_off(tmp_path / "cube.off", *cube())
    write_off(tmp_path / "far.off", moved(cube()[0], (5, 0, 0)), cube()[1])
    back = [1, 0, 0, -4.5, 0, 1, 0, 0.5, 0, 0, 1, 0.5, 0, 0, 0, 1]
    p = project(tmp_path / "back.mlp", [("cube.off", IDENTITY), ("far.off", back)])
    proc, out = render(tmp_path, "--colour", "intersecting", p, name="back.png")
    assert proc.returncode == 0, proc.stderr
    assert red(pixels(out)).sum() > 100
    p = project(tmp_path / "stay.mlp", [("cube.off", IDENTITY), ("far.off", IDENTITY)])
    proc, out = render(tmp_path, "--colour", "intersecting", p, name="stay.png")
    assert proc.returncode == 0, proc.stderr
    assert "0 intersecting pairs" in proc.stderr
    assert not red(pixels(out)).any()


def test_clearance_red_below_tau(tmp_path):
    """Two unit cubes 0.1 apart along z: red where they face each other
    when tau = 0.2, nowhere when tau = 0.05."""
    V, F = cube()
    a = write_off(tmp_path / "a.off", V, F)
    b = write_off(tmp_path / "b.off", moved(V, (0.3, 0.3, 1.1)), F)
    view = ("--view", "0.3,1,0.2")  # from the side: the gap is in sight
    proc, out = render(tmp_path, "--colour", "clearance", "--tau", 0.2, *view, a, b, name="c1.png")
    assert proc.returncode == 0, proc.stderr
    assert "minimum clearance 0.1" in proc.stderr
    assert red(pixels(out)).sum() > 50
    proc, out = render(tmp_path, "--colour", "clearance", "--tau", 0.05, *view, a, b, name="c2.png")
    assert proc.returncode == 0, proc.stderr
    assert not red(pixels(out)).any()


def test_new_faces_are_orange(tmp_path):
    V, F = cube()
    before = write_off(tmp_path / "open.off", V, F[2:])
    after = write_off(tmp_path / "closed.off", V, F)
    view = ("--view", "0.3,0.4,1")  # the z = 0 side, where the faces were added
    proc, out = render(tmp_path, "--colour", "new-faces", "--before", before, *view, after)
    assert proc.returncode == 0, proc.stderr
    assert "2 of 12 faces are not in" in proc.stderr
    assert orange(pixels(out)).sum() > 100
    proc, out = render(tmp_path, "--colour", "new-faces", "--before", after, *view, after,
                       name="same.png")
    assert not orange(pixels(out)).any()


@pytest.mark.parametrize("args,message", [
    (["missing.off"], "cannot"),
    (["--colour", "rainbow", "CUBE"], "unknown --colour rainbow"),
    (["--colour", "clearance", "CUBE"], "needs --tau"),
    (["--colour", "new-faces", "CUBE"], "needs --before"),
    (["--size", "3,3", "CUBE"], "expected --size"),
    (["PROJECT"], "which does not exist"),
])
def test_bad_input_says_what_is_wrong(tmp_path, args, message):
    cube_file = write_off(tmp_path / "cube.off", *cube())
    project = tmp_path / "p.mlp"
    project.write_text('<MeshLabProject><MeshGroup><MLMesh label="x" filename="gone.ply">'
                       '<MLMatrix44>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</MLMatrix44></MLMesh>'
                       '</MeshGroup></MeshLabProject>')
    args = [str(cube_file) if a == "CUBE" else str(project) if a == "PROJECT"
            else str(tmp_path / a) if a.endswith(".off") else a for a in args]
    proc, out = render(tmp_path, *args)
    assert proc.returncode != 0
    assert message in proc.stderr, proc.stderr
    assert not out.exists()


def test_the_picture_must_be_a_png(tmp_path):
    src = write_off(tmp_path / "cube.off", *cube())
    proc = subprocess.run([str(RENDER), str(src), "-o", str(tmp_path / "out.jpg")],
                          capture_output=True, text=True)
    assert proc.returncode != 0 and "must be a .png" in proc.stderr
