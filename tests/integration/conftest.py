"""Helpers of the integration tests: the real meshlabserver from the private
prefix (scripts/meshlabserver), .mlx scripts built from the filters' own
parameter declarations, small meshes written in every format, and the
independent checker `meshcheck` from ../shared/tools."""
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from xml.sax.saxutils import escape
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.append(str(ROOT / "tests"))  # shapes.py and environment.py, shared with the Python module's tests
from shapes import write_off  # noqa: E402,F401
from environment import (BUILD, DATA, MESHCHECK, SHARED, VENDOR, Host, meshcheck, need,  # noqa: E402,F401
                         require_meshcheck, require_shared_data)

PLUGIN_DIR = BUILD / "plugins-out"


_probe_cache = None


def probe():
    """Every MeshMend plugin's filters and parameters, as the plugins declare them."""
    global _probe_cache
    if _probe_cache is None:
        plugins = sorted(str(p) for p in PLUGIN_DIR.glob("*.so"))
        out = subprocess.run([str(BUILD / "tests" / "plugin_probe"), *plugins],
                             capture_output=True, text=True, check=True).stdout
        _probe_cache = json.loads(out)["plugins"]
    return _probe_cache


def filters():
    return {f["name"]: f for p in probe() for f in p["filters"]}


def mlx(*steps):
    """A filter script. Each step is (filter name, {param: value}); every
    declared parameter is written as MeshLab itself writes it (as Debian's
    meshlabserver requires), with the filter's default unless given."""
    lines = ["<!DOCTYPE FilterScript>", "<FilterScript>"]
    for name, values in steps:
        declared = filters()[name]["parameters"]
        unknown = set(values) - {p["name"] for p in declared}
        assert not unknown, f"{name} has no parameters {unknown}"
        lines.append(f' <filter name="{escape(name, {chr(34): "&quot;"})}">')
        for p in declared:
            element = ET.fromstring(p["xml"])
            if p["name"] in values:
                v = values[p["name"]]
                element.set("value", ("true" if v else "false") if isinstance(v, bool) else str(v))
            lines.append("  " + ET.tostring(element, encoding="unicode"))
        lines.append(" </filter>")
    lines.append("</FilterScript>")
    return "\n".join(lines) + "\n"


class Run:
    def __init__(self, proc, reports):
        self.returncode = proc.returncode
        self.log = proc.stdout + proc.stderr
        self.reports = reports

    @property
    def report(self):
        assert self.reports, f"no report written; log:\n{self.log[-3000:]}"
        return self.reports[-1]


def run_server(tmp_path, inputs, script_text, outputs=(), timeout=600):
    """Runs scripts/meshlabserver on `inputs` with the script text; returns the
    exit code, the whole log and the JSON reports the filters wrote (report
    paths are {report0}, {report1}... placeholders in the script text)."""
    reports = []
    for i in range(script_text.count("{report")):
        path = tmp_path / f"report{i}.json"
        if path.exists():
            path.unlink()
        script_text = script_text.replace("{report%d}" % i, str(path))
        reports.append(path)
    script = tmp_path / "script.mlx"
    script.write_text(script_text)
    cmd = [str(ROOT / "scripts" / "meshlabserver")]
    for i in inputs:
        cmd += ["-i", str(i)]
    for o in outputs:  # a path (the current layer), or (path, layer index)
        path, layer = o if isinstance(o, tuple) else (o, None)
        cmd += ["-o", str(path)] + (["-l", str(layer)] if layer is not None else [])
    cmd += ["-s", str(script)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return Run(proc, [json.loads(p.read_text()) for p in reports if p.exists()])


# ---- small meshes in every format ------------------------------------------

def float_exact(src, dst):
    """A copy of the OFF file `src` whose coordinates are floats (rounded
    once, written exactly), faces (triangles or polygons) as they are: a float
    host (2020.09) and a double host then read the same coordinates, so that
    their results differ only by what each stores, not by the input's
    rounding on loading."""
    lines = [l.split("#")[0].split() for l in Path(src).read_text().splitlines()]
    lines = [l for l in lines if l]
    assert lines[0][0].endswith("OFF"), f"{src}: not an OFF file"
    nv, nf = int(lines[1][0]), int(lines[1][1])
    V = np.array([l[:3] for l in lines[2:2 + nv]], float).astype(np.float32).astype(float)
    F = [[int(w) for w in l[1:1 + int(l[0])]] for l in lines[2 + nv:2 + nv + nf]]
    return write_off(dst, V, F)


def write_ply(path, V, F):
    """An ASCII PLY file (float coordinates in the header; values written
    exactly, as the readers round them)."""
    with open(path, "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {len(F)}\nproperty list uchar int vertex_indices\n"
                "end_header\n")
        for v in V:
            f.write(" ".join(repr(float(c)) for c in v) + "\n")
        for t in F:
            f.write(f"{len(t)} " + " ".join(map(str, t)) + "\n")
    return path


def write_obj(path, V, F):
    with open(path, "w") as f:
        for v in V:
            f.write("v " + " ".join(repr(float(c)) for c in v) + "\n")
        for t in F:
            f.write("f " + " ".join(str(i + 1) for i in t) + "\n")
    return path


def write_stl(path, V, F):
    with open(path, "w") as f:
        f.write("solid m\n")
        for t in F:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for i in t:
                f.write("   vertex " + " ".join(repr(float(c)) for c in V[i]) + "\n")
            f.write("  endloop\n endfacet\n")
        f.write("endsolid m\n")
    return path


WRITERS = {"off": write_off, "ply": write_ply, "obj": write_obj, "stl": write_stl}


def cube():
    V = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
    F = [(0, 2, 1), (1, 2, 3), (4, 5, 6), (5, 7, 6), (0, 1, 4), (1, 5, 4),
         (2, 6, 3), (3, 6, 7), (0, 4, 2), (2, 4, 6), (1, 3, 5), (3, 7, 5)]
    return V, F


# ---- reading meshlabserver's output (binary or ASCII PLY) ---------------------

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


def read_ply(path):
    """Vertices (float64 from the stored values), triangles, and the vertex
    properties by name."""
    data = path.read_bytes()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt = header[1].split()[1]
    elements = []
    for line in header:
        w = line.split()
        if w and w[0] == "element":
            elements.append((w[1], int(w[2]), []))
        elif w and w[0] == "property":
            elements[-1][2].append(w[1:])
    if fmt == "ascii":
        tokens = data[end:].split()
        pos, out = 0, {}
        for name, count, props in elements:
            rows = []
            for _ in range(count):
                row = []
                for p in props:
                    if p[0] == "list":
                        k = int(tokens[pos]); pos += 1
                        row.append([int(x) for x in tokens[pos:pos + k]]); pos += k
                    else:
                        row.append(float(tokens[pos])); pos += 1
                rows.append(row)
            out[name] = (props, rows)
        vprops, vrows = out["vertex"]
        names = [p[-1] for p in vprops]
        values = {n: np.array([r[i] for r in vrows], float) for i, n in enumerate(names)}
        fi = [p[-1] for p in out["face"][0]].index("vertex_indices")
        F = np.array([r[fi] for r in out["face"][1]], np.int64)
        return np.stack([values["x"], values["y"], values["z"]], 1), F, values
    assert fmt == "binary_little_endian", fmt
    pos, V, F, values = end, None, None, {}
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dtype = np.dtype([(p[1], "<" + _PLY_TYPES[p[0]]) for p in props])
            table = np.frombuffer(data, dtype=dtype, count=count, offset=pos)
            pos += dtype.itemsize * count
            if name == "vertex":
                values = {p[1]: table[p[1]].astype(float) for p in props}
                V = np.stack([values["x"], values["y"], values["z"]], 1)
            continue
        assert name == "face", props
        rows = []
        for _ in range(count):
            row = None
            for p in props:
                if p[0] == "list":
                    ct, it = "<" + _PLY_TYPES[p[1]], "<" + _PLY_TYPES[p[2]]
                    k = int(np.frombuffer(data, ct, 1, pos)[0]); pos += np.dtype(ct).itemsize
                    idx = np.frombuffer(data, it, k, pos); pos += np.dtype(it).itemsize * k
                    if p[3] == "vertex_indices":
                        row = idx
                else:
                    pos += np.dtype("<" + _PLY_TYPES[p[0]]).itemsize
            rows.append(row)
        F = np.array(rows, np.int64)
    return V, F, values
