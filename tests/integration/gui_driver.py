"""Drives a real MeshLab GUI (2020.09 from the private prefix, scripts/meshlab,
or a 2025.07 build of scripts/hosts) on a virtual display of its own: starts
Xvfb and MeshLab, clicks and types with xdotool, takes screenshots with
ImageMagick's import, and finds text on the screen with tesseract (word
boxes), so that tests need no fixed pixel positions for menus, dialogs and
parameters."""
import datetime
import os
import re
import shutil
import subprocess
import time
from pathlib import Path

from conftest import BUILD, filters

PREFIX = BUILD / "meshlab-prefix"
SCREEN = (1280, 1024)
SEARCH = (SCREEN[0] - 22, 46)  # the filter search (magnifier) at the right end of the toolbar


def require_tools():
    for tool in ("Xvfb", "xdotool", "import", "convert", "tesseract"):
        assert shutil.which(tool), f"{tool} missing: scripts/setup installs it"


def quiet_home(folder, double):
    """A HOME whose MeshLab (2022 and later) settings answer its first-start
    questions (anonymous statistics, update check), so the window opens
    without a dialog in front."""
    config = Path(folder) / ".config" / "VCG"
    config.mkdir(parents=True, exist_ok=True)
    today = datetime.date.today()
    checked = f"{today:%a} {today:%b} {today.day} {today.year}"  # QDate::toString()
    (config / f"MeshLab_64bit_{'dp' if double else 'fp'}.conf").write_text(
        f"[General]\ninformativeShown=true\ndontRemindMeToSendEmail=true\n"
        f"lastTimeMeshLabVersionCheckedOnStart={checked}\n")
    return Path(folder)


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

    def __init__(self, workdir, files=(), geometry=SCREEN, prefix=PREFIX, host=None, executable=None):
        """MeshLab 2020.09 from `prefix`, or the GUI of a scripts/hosts `host`
        (environment.Host) in a HOME of its own; `executable` another copy of
        that host's MeshLab."""
        require_tools()
        if executable is None:
            executable = Path(prefix) / "bin" / "meshlab"
            if host is not None:
                host.require_gui()
                executable = host.gui
        assert executable.exists(), f"no MeshLab at {executable}: run scripts/setup or scripts/hosts build"
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
        if host is not None:
            self.env["HOME"] = str(quiet_home(self.workdir / "home", host.double))
        self.log_path = self.workdir / "meshlab.log"
        self.log_file = open(self.log_path, "w")
        self.meshlab = subprocess.Popen(
            [str(executable), *(str(Path(f).resolve()) for f in files)],
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
    def words(self, png=None, region=None, readings=([], ["-negate"])):
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
        for negate in readings:
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
            shot = Path(png) if png else self.screenshot(self.workdir / "ocr.png")
            # The first match is looked for as shown, then negated (light text
            # on dark); the lowest one needs both readings at once.
            hits = []
            for readings in ([[], ["-negate"]],) if last else ([[]], [["-negate"]]):
                words = self.words(shot, region, readings=readings)
                hits = [words[i] for i in range(len(words) - len(wanted) + 1)
                        if all(_same(words[i + k].text, wanted[k]) for k in range(len(wanted)))]
                if hits:
                    break
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

    def run_script(self, script, reports, timeout=600):
        """Runs a filter script as a user of MeshLab 2022 and later does:
        Filters > Show current filter script, Open Script (`script`, in the
        working folder), Apply Script. Waits until every file of `reports`
        exists (each filter writes its report_file when it has run)."""
        self.open_menu("Filters", "Show current filter script")
        window = self.wait_for_window("^Dialog$")
        time.sleep(0.8)
        shape = self.xdotool("getwindowgeometry", window)
        x, y = map(int, re.search(r"Position: (\d+),(\d+)", shape).groups())
        w, h = map(int, re.search(r"Geometry: (\d+)x(\d+)", shape).groups())
        box = (x, y, x + w, y + h)
        button = self.find("Open Script", region=box, timeout=5)
        assert button, "no Open Script button in the filter script dialog"
        self.click(*button.center)
        self.wait_for_window("^Open Filter Script File$")
        time.sleep(0.8)
        self.type(Path(script).name)
        self.key("Return")
        time.sleep(1.0)
        button = self.find("Apply Script", region=box, timeout=5)
        assert button, "no Apply Script button in the filter script dialog"
        self.click(*button.center)
        end = time.time() + timeout
        while not all(Path(r).exists() for r in reports):
            assert self.alive(), "MeshLab exited: " + self.log_path.read_text()[-2000:]
            failed = self.windows("^Filter Failure|^Error|^Warning")
            assert not failed, "the script failed: " + self.log_path.read_text()[-2000:]
            assert time.time() < end, "the script did not finish: " + self.log_path.read_text()[-2000:]
            time.sleep(0.5)
        time.sleep(1.0)

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


def parameter(filter_name, name):
    """A parameter's declaration: description (the dialog's label), tooltip,
    type, default (enum index or text)."""
    for p in filters()[filter_name]["parameters"]:
        if p["name"] == name:
            xml = p["xml"]
            get = lambda key: re.search(f' {key}="([^"]*)"', xml).group(1)
            choices = dict(re.findall(r' enum_val(\d+)="([^"]*)"', xml))
            return {"description": get("description"), "tooltip": get("tooltip"),
                    "type": get("type"), "value": get("value"),
                    "choices": [choices[str(i)] for i in range(len(choices))]}
    raise KeyError(f"{filter_name} has no parameter {name}")


class Dialog:
    """A filter's parameter dialog (a window titled with the filter's name)."""

    def __init__(self, gui, name):
        self.gui, self.name = gui, name
        gui.click(*SEARCH)
        gui.type(name)
        time.sleep(1.0)
        gui.key("Down")
        gui.key("Return")
        self.window = gui.wait_for_window("^" + re.escape(name) + "$", timeout=20)
        time.sleep(0.8)
        shape = gui.xdotool("getwindowgeometry", self.window)
        x, y = map(int, re.search(r"Position: (\d+),(\d+)", shape).groups())
        w, h = map(int, re.search(r"Geometry: (\d+)x(\d+)", shape).groups())
        self.box = (x, y, x + w, y + h)

    def label(self, name):
        p = parameter(self.name, name)
        words = p["description"].split()[:3]
        # The lowest match: the filter's description above the parameters may use the words too.
        found = self.gui.find(" ".join(words), region=self.box, timeout=5, last=True)
        assert found, f"no label {p['description']!r} in the dialog of {self.name}"
        return found, p

    def widget_at(self, label):
        """A point inside the widget on the label's row: the widgets of the
        dialog's second column reach its right margin."""
        return self.box[2] - 40, label.center[1]

    def set(self, name, value):
        label, p = self.label(name)
        if p["type"] == "RichBool":
            if (p["value"] == "true") != bool(value):
                self.gui.click(*label.center)
        elif p["type"] == "RichEnum":  # open the list, go to its first entry, then down
            self.gui.click(*self.widget_at(label))
            time.sleep(0.8)
            self.gui.key("Home")
            for _ in range(int(value)):
                self.gui.key("Down")
            self.gui.key("Return")
        else:
            x, y = self.widget_at(label)
            if p["type"] == "RichAbsPerc":  # spin boxes under "world unit" and "perc on"
                unit = self.gui.find("world unit", region=self.box, timeout=3)
                assert unit, "no absolute field"
                x, y = unit.center[0], unit.center[1] + 22
            self.gui.click(x, y)
            self.gui.key("ctrl+a")
            self.gui.type(str(value))
            self.gui.key("Tab")

    def tooltip(self, name, path):
        """Hovers the parameter's label until its tooltip shows; screenshot of
        the dialog with the tooltip; returns the words read there. (MeshLab
        2020.09 gives tooltips to the labels of booleans, numbers, strings
        and distances; an enumeration's label has none.)"""
        label, p = self.label(name)
        self.gui.hover(*label.center, wait=2.5)
        x0, y0, x1, y1 = self.box
        crop = (0, 0, min(SCREEN[0], x1 + 460), min(SCREEN[1], y1 + 140))
        path = self.gui.screenshot(path, crop=crop)
        return self.gui.text(path), p["tooltip"]

    def apply(self, timeout=300):
        """Clicks Apply and waits for MeshLab's "Applied filter" line in its log
        (the GUI prints its log on stdout); returns the log lines the filter
        added. A failure box fails the test."""
        before = len(self.gui.log_path.read_text().splitlines())
        apply = self.gui.find("Apply", region=self.box, timeout=5, last=True)
        assert apply, f"no Apply button in the dialog of {self.name}"
        self.gui.click(*apply.center)
        end = time.time() + timeout
        while True:
            lines = self.gui.log_path.read_text().splitlines()[before:]
            # "Applied filter NAME" in 2020.09, "Applied filter: NAME" in 2025.07.
            if any(re.search("Applied filter:? " + re.escape(self.name), line) for line in lines):
                break
            assert not self.gui.windows("^Filter Failure|^Error"), \
                f"{self.name} failed: " + "\n".join(lines[-20:])
            assert time.time() < end, f"{self.name} did not finish: " + "\n".join(lines[-20:])
            time.sleep(0.5)
        time.sleep(1.0)  # the view redraws
        return lines

    def close(self):
        close = self.gui.find("Close", region=self.box, timeout=5, last=True)
        assert close, f"no Close button in the dialog of {self.name}"
        self.gui.click(*close.center)
        time.sleep(0.8)


def _same(read, wanted):
    """OCR-tolerant word comparison: case and punctuation around words ignored."""
    strip = lambda s: re.sub(r"^[^\w]+|[^\w]+$", "", s).lower()
    return strip(read) == strip(wanted)
