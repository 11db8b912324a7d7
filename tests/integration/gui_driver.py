"""Drives the real MeshLab GUI (the private prefix, scripts/meshlab) on a
virtual display of its own: starts Xvfb and MeshLab, clicks and types with
xdotool, takes screenshots with ImageMagick's import, and finds text on the
screen with tesseract (word boxes), so that tests need no fixed pixel
positions for menus, dialogs and parameters."""
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

from conftest import BUILD

PREFIX = BUILD / "meshlab-prefix"
SCREEN = (1280, 1024)


def require_tools():
    for tool in ("Xvfb", "xdotool", "import", "convert", "tesseract"):
        assert shutil.which(tool), f"{tool} missing: scripts/setup installs it"
    assert (PREFIX / "bin" / "meshlab").exists(), f"no private MeshLab in {PREFIX}: run scripts/setup"


class Word:
    def __init__(self, text, left, top, width, height):
        self.text, self.left, self.top, self.width, self.height = text, left, top, width, height

    @property
    def center(self):
        return self.left + self.width // 2, self.top + self.height // 2

    def __repr__(self):
        return f"{self.text}@{self.left},{self.top}"


class MeshLabGui:
    """One MeshLab GUI process on its own Xvfb display, in `workdir` (where
    MeshLab's render plugin writes shaders.log when a shader fails)."""

    def __init__(self, workdir, files=(), geometry=SCREEN, prefix=PREFIX):
        require_tools()
        self.workdir = Path(workdir)
        self.workdir.mkdir(parents=True, exist_ok=True)
        read, write = os.pipe()
        self.xvfb = subprocess.Popen(
            ["Xvfb", "-displayfd", str(write), "-screen", "0", f"{geometry[0]}x{geometry[1]}x24",
             "-nolisten", "tcp"], pass_fds=(write,), stderr=subprocess.DEVNULL)
        os.close(write)
        number = b""
        while not number.endswith(b"\n"):
            chunk = os.read(read, 16)
            assert chunk, "Xvfb did not start"
            number += chunk
        os.close(read)
        self.env = dict(os.environ, DISPLAY=":" + number.decode().strip())
        self.log_path = self.workdir / "meshlab.log"
        self.log_file = open(self.log_path, "w")
        self.meshlab = subprocess.Popen(
            [str(Path(prefix) / "bin" / "meshlab"), *(str(Path(f).resolve()) for f in files)],
            cwd=self.workdir, env=self.env, stdout=self.log_file, stderr=subprocess.STDOUT)
        self.window = self.wait_for_window("^MeshLab 20", timeout=60)
        self.fill_screen(geometry)
        time.sleep(2)  # the first frame

    def fill_screen(self, geometry):
        """The main window over the whole screen (a large 3D view); retried while
        the window manager-less X server has not mapped it yet."""
        for _ in range(20):
            self.xdotool("windowmove", self.window, 0, 0, check=False)
            self.xdotool("windowsize", self.window, *geometry, check=False)
            time.sleep(0.5)
            shape = self.xdotool("getwindowgeometry", self.window, check=False)
            size = re.search(r"Geometry: (\d+)x(\d+)", shape)
            if size and int(size.group(1)) >= geometry[0] - 8:
                return
        raise AssertionError(f"MeshLab's window did not take the size {geometry}: {shape}")

    # ---- X helpers -------------------------------------------------------------
    def xdotool(self, *args, check=True):
        out = subprocess.run(["xdotool", *map(str, args)], env=self.env, capture_output=True,
                             text=True)
        if check:
            assert out.returncode == 0, f"xdotool {args}: {out.stderr}"
        return out.stdout

    def windows(self, name):
        out = subprocess.run(["xdotool", "search", "--onlyvisible", "--name", name],
                             env=self.env, capture_output=True, text=True)
        return out.stdout.split()

    def wait_for_window(self, name, timeout=20):
        end = time.time() + timeout
        while time.time() < end:
            found = self.windows(name)
            if found:
                return found[0]
            assert self.alive(), "MeshLab exited: " + self.log_path.read_text()[-2000:]
            time.sleep(0.3)
        raise AssertionError(f"no window named {name!r} after {timeout} s")

    def alive(self):
        return self.meshlab.poll() is None

    def click(self, x, y, button=1):
        self.xdotool("mousemove", x, y)
        time.sleep(0.15)
        self.xdotool("click", button)
        time.sleep(0.4)

    def hover(self, x, y, wait=1.8):
        self.xdotool("mousemove", x + 1, y)
        time.sleep(0.1)
        self.xdotool("mousemove", x, y)
        time.sleep(wait)

    def key(self, *keys):
        self.xdotool("key", *keys)
        time.sleep(0.3)

    def type(self, text):
        self.xdotool("type", "--delay", "30", text)
        time.sleep(0.3)

    def screenshot(self, path, crop=None):
        """The whole screen (or crop = (x, y, w, h)) as a PNG."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        raw = path.with_suffix(".raw.png")
        subprocess.run(["import", "-window", "root", str(raw)], env=self.env, check=True)
        args = ["convert", str(raw)]
        if crop:
            args += ["-crop", "%dx%d+%d+%d" % (crop[2], crop[3], crop[0], crop[1]), "+repage"]
        subprocess.run(args + [str(path)], check=True)
        raw.unlink()
        return path

    # ---- reading the screen ------------------------------------------------------
    def words(self, png=None, region=None):
        """The words tesseract reads on the screen (or in `png`; only within
        region = (x0, y0, x1, y1) when given), with their boxes in screen
        pixels (read at twice the size for small GUI fonts)."""
        png = Path(png) if png else self.screenshot(self.workdir / "ocr.png")
        x0 = y0 = 0
        if region:
            x0, y0 = region[0], region[1]
            crop = self.workdir / "ocr_region.png"
            subprocess.run(["convert", str(png), "-crop", "%dx%d+%d+%d" % (
                region[2] - x0, region[3] - y0, x0, y0), "+repage", str(crop)], check=True)
            png = crop
        found = []
        # Read twice: as shown, and negated, for light text on highlighted
        # (dark) menu entries and title bars.
        for negate in ([], ["-negate"]):
            big = png.with_name(png.stem + "_x2.png")
            subprocess.run(["convert", str(png), "-colorspace", "gray", *negate, "-resize", "200%",
                            str(big)], check=True)
            tsv = subprocess.run(["tesseract", str(big), "-", "--psm", "11", "tsv"],
                                 capture_output=True,
                                 text=True).stdout
            big.unlink()
            for line in tsv.splitlines()[1:]:
                cols = line.split("\t")
                if len(cols) == 12 and cols[11].strip():
                    left, top, width, height = (int(c) // 2 for c in cols[6:10])
                    found.append(Word(cols[11].strip(), left + x0, top + y0, width, height))
        return found

    def text(self, png=None):
        return " ".join(w.text for w in self.words(png))

    def find(self, phrase, png=None, region=None, timeout=0, last=False):
        """The first (or lowest on the screen, with `last`) occurrence of
        `phrase` (words in a row) on the screen, as the Word of its first word;
        None when absent. region = (x0, y0, x1, y1)."""
        end = time.time() + timeout
        wanted = phrase.split()
        while True:
            words = self.words(png, region)
            hits = [words[i] for i in range(len(words) - len(wanted) + 1)
                    if all(_same(words[i + k].text, wanted[k]) for k in range(len(wanted)))]
            if hits:
                return max(hits, key=lambda w: w.top) if last else hits[0]
            if time.time() >= end or png:
                return None
            time.sleep(0.5)

    # ---- MeshLab ------------------------------------------------------------------------
    def open_menu(self, *path):
        """Opens a menu of the menu bar and walks down its submenus (by their
        text on the screen); clicks the last entry."""
        bar = self.find(path[0], region=(0, 0, SCREEN[0], 24), timeout=5)
        assert bar, f"no menu {path[0]!r} in the menu bar"
        self.click(*bar.center)
        for i, entry in enumerate(path[1:], 1):
            item = self.find(entry, region=(0, 24, SCREEN[0], SCREEN[1]), timeout=5)
            assert item, f"no entry {entry!r} in menu {path[:i]}"
            if i < len(path) - 1:
                self.hover(*item.center, wait=0.8)
            else:
                self.click(*item.center)

    def apply_shader(self, gdp, wait=3):
        """Render > Shaders > gdp. MeshLab's render plugin compiles the shader
        then: on a compile or link error it writes shaders.log into its working
        folder and shows a message box titled "Meshlab"; on success it opens the
        shader's uniform dialog (a window titled "Form"). Returns (compiled, text
        of shaders.log)."""
        log = self.workdir / "shaders.log"
        if log.exists():
            log.unlink()
        self.open_menu("Render", "Shaders", gdp)
        time.sleep(wait)
        error_box = self.windows("^Meshlab$")
        dialog = self.windows("^Form$")
        text = log.read_text() if log.exists() else ""
        compiled = bool(dialog) and not error_box and not text
        return compiled, text

    def close(self):
        if self.alive():
            self.meshlab.terminate()
            try:
                self.meshlab.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.meshlab.kill()
        self.log_file.close()
        self.xvfb.terminate()
        self.xvfb.wait(timeout=10)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _same(read, wanted):
    """OCR-tolerant word comparison: case and punctuation around words ignored."""
    strip = lambda s: re.sub(r"^[^\w]+|[^\w]+$", "", s).lower()
    return strip(read) == strip(wanted)
