"""scripts/package: a tarball per host whose plugins, installed into a clean
prefix of that host as its INSTALL says, load and run there: through
pymeshlab.load_plugin for the double hosts, and in a fresh copy of the
MeshLab GUI (MeshLab's own plugins and executable, MeshMend's from the
package) for the GUI hosts."""
import os
import re
import shutil
import subprocess
import tarfile
import time

import pytest

from conftest import ROOT, Host, cube, write_off
from gui_driver import MeshLabGui

HOSTS = {"2020.09": [], "2025.07": [], "2025.07d": ["--double"], "2022.02d": ["--double"]}


def package(host, tmp_path):
    """Builds the host's package and unpacks it into tmp_path; its folder."""
    version = host.rstrip("d")
    proc = subprocess.run([str(ROOT / "scripts" / "package"), "--meshlab", version, *HOSTS[host]],
                          capture_output=True, text=True, timeout=3600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    tarball = proc.stdout.strip().splitlines()[-1]
    assert tarball.endswith(f"meshlab-{host}-linux-x86_64.tar.gz"), tarball
    with tarfile.open(tarball) as t:
        t.extractall(tmp_path / "unpacked")
    (folder,) = (tmp_path / "unpacked").iterdir()
    install = (folder / "INSTALL").read_text()
    assert f"MeshLab {host}" in install and "only into MeshLab" in install
    return folder


@pytest.mark.parametrize("name", ["2025.07d", "2022.02d"])
def test_a_double_package_loads_into_pymeshlab(name, tmp_path):
    host = Host(name)
    host.require_pymeshlab()
    host.require_plugins()
    folder = package(name, tmp_path)
    plugins = sorted((folder / "plugins").glob("*.so"))
    assert [p.name for p in plugins] == [p.name for p in sorted(host.plugin_dir.glob("*.so"))]
    V, F = cube()
    mesh = write_off(tmp_path / "open.off", V, F[1:])
    out = host.pymeshlab_job({"plugins": [str(p) for p in plugins], "meshes": [str(mesh)],
                              "steps": [{"filter": "meshmend_fill_holes", "params": {"max_diameter": 0}},
                                        {"script": str(folder / "samples" / "inspect.mlx")}]}, tmp_path)
    assert all("error" not in p for p in out["plugins"]), out["plugins"]
    assert out["steps"][0]["result"]["holes_filled"] == 1, out["steps"]
    assert "error" not in out["steps"][1] and out["layers"][0]["faces"] == 12


@pytest.mark.parametrize("name", ["2025.07", "2025.07d", "2020.09"])
def test_a_gui_package_loads_into_a_clean_meshlab(name, tmp_path):
    """MeshLab's executable and its own plugins in a new folder, MeshMend's
    plugins and shaders copied there from the package: MeshLab loads them all."""
    host = Host(name)
    host.require_gui() if name != "2020.09" else host.require_plugins()
    folder = package(name, tmp_path)
    prefix = tmp_path / "meshlab"
    if name == "2020.09":  # Debian's layout: bin/meshlab, lib/<arch>/meshlab/plugins
        system = "/usr/lib/x86_64-linux-gnu/meshlab"
        plugins = prefix / "lib" / "x86_64-linux-gnu" / "meshlab" / "plugins"
        plugins.mkdir(parents=True)
        (prefix / "bin").mkdir()
        shutil.copy("/usr/bin/meshlab", prefix / "bin" / "meshlab")
        os.symlink(f"{system}/libmeshlab-common.so", plugins.parent / "libmeshlab-common.so")
        for p in os.listdir(f"{system}/plugins"):
            os.symlink(f"{system}/plugins/{p}", plugins / p)
        gui_args = {"prefix": prefix}
    else:  # MeshLab's own build: meshlab, plugins/ and shaders/ side by side
        distrib = host.gui.parent
        plugins = prefix / "plugins"
        plugins.mkdir(parents=True)
        shutil.copy(distrib / "meshlab", prefix / "meshlab")
        for lib in distrib.glob("libmeshlab-common.so*"):
            os.symlink(lib.resolve(), prefix / lib.name)
        for p in (distrib / "plugins").iterdir():
            if "mend_" not in p.name:
                os.symlink(p.resolve(), plugins / p.name)
        (prefix / "shaders").mkdir()
        for s in folder.glob("shaders/*"):
            shutil.copy(s, prefix / "shaders" / s.name)
        gui_args = {"host": host, "executable": prefix / "meshlab"}
    for p in folder.glob("plugins/*.so"):
        shutil.copy(p, plugins / p.name)
    V, F = cube()
    with MeshLabGui(tmp_path / "gui", [write_off(tmp_path / "cube.off", V, F)], **gui_args) as gui:
        time.sleep(1)
        maps = open(f"/proc/{gui.meshlab.pid}/maps").read()
        loaded = {m for m in re.findall(r"(\S*/plugins/[^/\s]*mend_[^/\s]*\.so)", maps)}
        names = {os.path.basename(m) for m in loaded if m.startswith(str(plugins))}
        assert names == {p.name for p in folder.glob("plugins/*.so")}, (names, loaded)
