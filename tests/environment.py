"""What the Python test suites need from the machine, in one place: the
checker and the real meshes of ../shared, and the MeshLab hosts of
scripts/hosts (their plugins, GUI and pymeshlab). A missing piece skips the
test with a reason that starts with "missing:" (scripts/test lists them),
and fails it in CI (CI=true), where scripts/test provides everything."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BUILD = Path(os.environ.get("MESHMEND_BUILD_DIR", ROOT / "build"))
SHARED = Path(os.environ.get("MESHMEND_SHARED_DIR", ROOT.parent / "shared"))
DATA = SHARED / "data"
VENDOR = SHARED / "vendor"
MESHCHECK = Path(os.environ.get("MESHMEND_MESHCHECK", BUILD / "shared-tools" / "meshcheck"))


def need(present, what):
    """Skips ("missing: what") or, in CI, fails when `present` is false."""
    if present:
        return
    if os.environ.get("CI") == "true":
        pytest.fail(f"missing in CI: {what}", pytrace=False)
    pytest.skip(f"missing: {what}")


def require_meshcheck():
    need(MESHCHECK.is_file(), f"{MESHCHECK} (scripts/test builds it from ../shared/tools)")


def require_shared_data():
    need(DATA.is_dir(), f"{DATA} (the real meshes live in ../shared beside the project)")
    require_meshcheck()


def meshcheck(path, *args):
    """The independent checker's report on a mesh file."""
    require_meshcheck()
    out = subprocess.run([str(MESHCHECK), str(path), *args], capture_output=True, text=True)
    return json.loads(out.stdout) if out.stdout.strip() else {"exit": out.returncode}


class Host:
    """A MeshLab host of scripts/hosts: HOST, SCALAR, PLUGINS (folder),
    MESHLAB (GUI executable or empty), MESHLABSERVER, PYMESHLAB_PATH."""

    def __init__(self, name):
        proc = subprocess.run([str(ROOT / "scripts" / "hosts"), "env", name],
                              capture_output=True, text=True, env={**os.environ, "MESHMEND_BUILD_DIR": str(BUILD)})
        assert proc.returncode == 0, proc.stderr
        self.env = dict(line.split("=", 1) for line in proc.stdout.splitlines() if "=" in line)
        self.name = name
        self.double = self.env["SCALAR"] == "double"
        self.plugin_dir = Path(self.env["PLUGINS"])
        self.plugins = sorted(self.plugin_dir.glob("libfilter_mend_*.so")) if self.plugin_dir.is_dir() else []
        self.gui = Path(self.env["MESHLAB"]) if self.env["MESHLAB"] else None
        self.pymeshlab = Path(self.env["PYMESHLAB_PATH"]) if self.env["PYMESHLAB_PATH"] else None

    def require_plugins(self):
        need(self.plugins, f"MeshMend's plugins for MeshLab {self.name} ({self.plugin_dir}): "
                           f"scripts/hosts build {self.name}")

    def require_pymeshlab(self):
        need(VENDOR.is_dir(), f"{VENDOR} (pymeshlab is built from its sources there)")
        need(self.pymeshlab and (self.pymeshlab / "pymeshlab").is_dir(),
             f"pymeshlab for MeshLab {self.name}: scripts/hosts build {self.name}")

    def require_gui(self):
        self.require_plugins()
        need(self.gui and self.gui.is_file(), f"the MeshLab {self.name} GUI: scripts/hosts build {self.name}")

    def pymeshlab_job(self, job, tmp_path, timeout=900):
        """Runs a pymeshlab_job.py job in this host's pymeshlab; its output."""
        self.require_pymeshlab()
        path = tmp_path / f"job{len(list(tmp_path.glob('job*.json')))}.json"
        path.write_text(json.dumps(job))
        proc = subprocess.run([sys.executable, str(ROOT / "tests" / "integration" / "pymeshlab_job.py"),
                               str(path)], capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "PYTHONPATH": str(self.pymeshlab)})
        try:
            return json.loads(proc.stdout.strip().splitlines()[-1])
        except (json.JSONDecodeError, IndexError):
            raise AssertionError(f"pymeshlab job printed no JSON (exit {proc.returncode}):\n"
                                 f"{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}")
