"""Runs one job in a real pymeshlab (the one on PYTHONPATH) and prints what
happened as one JSON object on stdout; the integration tests start it in a
process of its own for each pymeshlab version (two cannot share a process).

    python3 pymeshlab_job.py JOB.json

JOB: {"plugins": [paths], "meshes": [paths], "steps": [step...],
      "save": folder or null, "describe": [python filter names]}
A step is {"filter": name, "params": {name: value}} or {"script": mlx path}.
A value {"abs": x} or {"percent": x} is passed as pymeshlab's absolute or
percentage value (the classes are named differently in 2022.2 and 2025.7).

Output: {"version", "plugins": [{"file", "error"?}], "describe": {name:
{"defaults": {...}, "types": {...}}}, "steps": [{"result": {...}} or
{"error", "exception"}], "layers": [{"id", "label", "vertices", "faces",
"selected_faces", "selected_vertices", "visible"}], "saved": {id: path}}.
A step that fails ends the job (the steps after it are not run), as in a
script; the layers are those of the document then."""
import contextlib
import io
import json
import math
import os
import sys
import tempfile

import numpy as np
import pymeshlab


def value_of(v):
    if isinstance(v, dict) and "abs" in v:
        cls = getattr(pymeshlab, "PureValue", None) or getattr(pymeshlab, "AbsoluteValue")
        return cls(v["abs"])
    if isinstance(v, dict) and "percent" in v:
        cls = getattr(pymeshlab, "PercentageValue", None) or getattr(pymeshlab, "Percentage")
        return cls(v["percent"])
    return v


def plain(v):
    """A JSON-able copy of a pymeshlab result value."""
    if isinstance(v, dict):
        return {k: plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if isinstance(v, np.ndarray):
        return [plain(x) for x in v.tolist()]
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return None if math.isnan(v) else float(v)
    return repr(v)


@contextlib.contextmanager
def c_stdout():
    """Captures what is printed, by C++ code on file descriptor 1 (pymeshlab
    2025.7) or through Python's sys.stdout (2022.2)."""
    sys.stdout.flush()
    saved = os.dup(1)
    python = io.StringIO()
    with tempfile.TemporaryFile(mode="w+") as f:
        os.dup2(f.fileno(), 1)
        text = io.StringIO()
        try:
            with contextlib.redirect_stdout(python):
                yield text
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            f.seek(0)
            text.write(f.read() + python.getvalue())


def describe(ms, name):
    """A filter's parameters: their defaults on the current mesh and their
    types as pymeshlab lists them."""
    with c_stdout() as text:
        pymeshlab.print_filter_parameter_list(name)
    types = {}
    for line in text.getvalue().splitlines():
        if line.startswith("\t") and " : " in line:
            pname, rest = line.strip().split(" : ", 1)
            types[pname] = rest.split(" = ")[0]
    return {"defaults": plain(ms.filter_parameter_values(name)), "types": types}


def layers(ms):
    out = []
    for m in ms:
        out.append({"id": m.id(), "label": m.label(), "vertices": m.vertex_number(),
                    "faces": m.face_number(), "selected_faces": m.selected_face_number(),
                    "selected_vertices": m.selected_vertex_number(), "visible": m.is_visible()})
    return out


def main():
    job = json.loads(open(sys.argv[1]).read())
    out = {"version": pymeshlab.__version__ if hasattr(pymeshlab, "__version__") else "",
           "plugins": [], "steps": [], "describe": {}}
    for path in job.get("plugins", []):
        entry = {"file": os.path.basename(path)}
        try:
            pymeshlab.load_plugin(path)
        except Exception as e:  # pymeshlab.PyMeshLabException
            entry["error"] = str(e)
            entry["exception"] = type(e).__name__
        out["plugins"].append(entry)
    ms = pymeshlab.MeshSet()
    ms.set_verbosity(True)  # pymeshlab 2022.2 prints nothing otherwise, parameter lists included
    with c_stdout():
        for path in job.get("meshes", []):
            ms.load_new_mesh(str(path))
    for name in job.get("describe", []):
        out["describe"][name] = describe(ms, name)
    ms.set_verbosity(False)
    for step in job.get("steps", []):
        try:
            if "script" in step:
                ms.load_filter_script(step["script"])
                ms.apply_filter_script()
                out["steps"].append({"result": {}})
            else:
                params = {k: value_of(v) for k, v in step.get("params", {}).items()}
                result = ms.apply_filter(step["filter"], **params)
                out["steps"].append({"result": plain(result or {})})
        except Exception as e:
            out["steps"].append({"error": str(e), "exception": type(e).__name__})
            break
    out["layers"] = layers(ms)
    if job.get("save"):
        os.makedirs(job["save"], exist_ok=True)
        out["saved"] = {}
        for m in ms:
            ms.set_current_mesh(m.id())
            path = os.path.join(job["save"], f"{m.id()}.ply")
            ms.save_current_mesh(path, binary=True)  # the host's scalar, exactly
            out["saved"][m.id()] = path
    sys.stdout.flush()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
