"""MeshMend's geometry core on NumPy arrays.

Every function takes a mesh as ``vertices`` (an ``(n, 3)`` array of real
coordinates) and ``faces`` (an ``(m, 3)`` array of integer vertex indices),
and returns new arrays plus ``report``: a dict with the keys the MeshLab
filters write to their ``report_file``. Options are keyword arguments: every
parameter of the matching MeshLab filter under its name and with its default
(apart from those naming layers or the selection of a MeshLab document,
which are array arguments here), ``report_file``, and the further options of
the core's ``XxxOptions`` structs (``help(meshmend.fill_holes)`` lists them).
The inputs are never modified.

Bad input raises ``InvalidInputError`` (a ``ValueError``) or
``TopologyError`` (also a ``ValueError``) with a message saying what to fix;
a wrong option type raises ``TypeError``. A result that misses its
contract (checked exactly on what is returned, as the filters check theirs:
remove_self_intersections, stitch_boundaries, stitch_sequence, close_gaps,
enforce_clearance) raises ``Error`` saying what does not hold, unless
``keep_partial=True``: then it is returned with ``report['contract_met']``
False and ``report['contract_failures']`` listing what failed. Long
operations release the GIL and stop on Ctrl-C; ``progress=callable(percent,
stage)`` reports progress, and returning ``False`` from it stops the
operation (``CancelledError``).

Output arrays: vertices float64 ``(n, 3)``, faces and indices int32.
"""

import importlib.machinery
import importlib.util
import functools
import inspect as _inspect
import json
import os
import sys
from typing import Any, Dict, List, NamedTuple, Optional, Tuple


def _import_numpy():
    try:
        import numpy

        return numpy
    except ImportError:
        pass
    # The module is built for Debian's python3; Debian's NumPy (python3-numpy)
    # is built for the same Python version and loads into any interpreter of
    # that version that lacks its own NumPy.
    debian = "/usr/lib/python3/dist-packages/numpy"
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    if os.path.isfile(os.path.join(debian, "core", "_multiarray_umath" + suffix)):
        spec = importlib.util.spec_from_file_location(
            "numpy", os.path.join(debian, "__init__.py"), submodule_search_locations=[debian])
        module = importlib.util.module_from_spec(spec)
        sys.modules["numpy"] = module
        try:
            spec.loader.exec_module(module)
        except Exception:
            del sys.modules["numpy"]
            raise
        return module
    raise ImportError(
        "meshmend needs NumPy: install Debian's python3-numpy (and use /usr/bin/python3), or "
        "NumPy for " + sys.executable)


def _import_core():
    try:
        from . import _core

        return _core
    except ImportError as e:
        here = os.path.dirname(os.path.abspath(__file__))
        built = sorted(f for f in os.listdir(here) if f.startswith("_core."))
        if any(f.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES)) for f in built):
            raise ImportError(f"meshmend's compiled part in {here} fails to load ({e}): "
                              f"rebuild MeshMend (scripts/setup)") from e
        raise ImportError(
            f"meshmend's compiled part ({', '.join(built) or 'missing'} in {here}) is not built "
            f"for Python {sys.version.split()[0]} ({sys.executable}) but for Debian's "
            f"/usr/bin/python3: use that, or build MeshMend with "
            f"-DPython_EXECUTABLE={sys.executable}") from e


_core = _import_core()
np = _import_numpy()

Error = _core.Error
InvalidInputError = _core.InvalidInputError
TopologyError = _core.TopologyError
CancelledError = _core.CancelledError
FACE_DEFECTS: Dict[str, int] = dict(_core.FACE_DEFECTS)
VERTEX_DEFECTS: Dict[str, int] = dict(_core.VERTEX_DEFECTS)

Arrays = Tuple[Any, Any]  # (vertices, faces)


# ---------------------------------------------------------------- results


class SplitResult(NamedTuple):
    meshes: List[Arrays]  # per input mesh, with the curves inserted (separate_meshes)
    curve_edges: List[Any]  # per input mesh: (k, 2) vertex pairs along the curves
    merged: Arrays  # all meshes in one, welded along the curves
    merged_curve_edges: Any  # (k, 2) vertex pairs of `merged`
    merged_part: Any  # per face of `merged`: the input mesh it came from
    report: Dict[str, Any]


class FindResult(NamedTuple):
    pairs: Any  # (k, 4): mesh_a, face_a, mesh_b, face_b
    segments: Optional[Arrays]  # (points, edges) with contacts=True, else None
    report: Dict[str, Any]


class SelfIntersectionResult(NamedTuple):
    vertices: Any
    faces: Any
    face_origin: Any  # per output face: the input face it was cut from
    removed: Optional[Arrays]  # the faces left out (keep_removed=True), else None
    report: Dict[str, Any]


class FillHolesResult(NamedTuple):
    vertices: Any  # input vertices first, in their order, then the new ones
    faces: Any  # input faces first (split ones keep their index for one half)
    new_faces: Any
    new_vertices: Any
    report: Dict[str, Any]


class TrimResult(NamedTuple):
    vertices: Any
    faces: Any
    vertex_index: Any  # per input vertex: its index in the output, -1 if dropped
    loop: Any  # the loop used, input vertex indices, in its direction
    removed: Arrays  # the removed faces and their vertices
    report: Dict[str, Any]


class StitchResult(NamedTuple):
    vertices: Any  # input vertices first, then the new ones (subdivision)
    faces: Any  # input faces first, then the new ones
    new_faces: Any
    new_vertices: Any
    report: Dict[str, Any]


class CloseGapsResult(NamedTuple):
    vertices: Any
    faces: Any
    vertex_index: Any  # per input vertex: its index in the output
    report: Dict[str, Any]


class MeasureClearanceResult(NamedTuple):
    vertex_clearance: List[Any]  # per mesh, per vertex: local clearance (capped at local_max)
    faces_below_tau: List[Any]  # per mesh, per face: closer than tau to some face
    report: Dict[str, Any]


class EnforceClearanceResult(NamedTuple):
    meshes: List[Arrays]  # per mesh: moved vertices, faces as given
    report: Dict[str, Any]


class PaintResult(NamedTuple):
    patch_of_face: Any  # per face: its patch id (report['patch_list'] describes each)
    report: Dict[str, Any]


class PatchesResult(NamedTuple):
    vertices: Any
    faces: Any
    face_origin: Any  # per output face: the input face it copies
    report: Dict[str, Any]
    removed: Optional[Arrays] = None  # the removed patches, welded (removed_mesh=True)


class SelectPatchesResult(NamedTuple):
    selected_faces: Any  # per face: in a chosen patch
    patch_of_face: Any  # per face: its patch id
    report: Dict[str, Any]  # patches_selected, faces_selected, selected_ids, notes


# ---------------------------------------------------------------- signatures


# ---------------------------------------------------------------- the filters' parameters
#
# Every parameter of a MeshMend filter is an option of the matching function
# here, under the same name and with the same default (tests/python/
# test_parity.py compares them with what the plugins declare), apart from
# those that name things of a MeshLab document (layers, the selection).
# Where the core's option has another name, the filter's name is taken too;
# an enum parameter takes the filter's index (a script's value) as well as
# the name; a distance takes mesh units or a percentage of the bounding box
# diagonal ("1%"), as the filter's does.

# Per function, per enum option: the choices' names in the filter's order.
FILTER_CHOICES: Dict[str, Dict[str, Tuple[str, ...]]] = {
    "fill_holes": {"fairing": ("laplacian_regression", "biharmonic", "harmonic", "flat")},
    "measure_clearance": {"scope": ("within_layers", "between_layers", "both")},
    "enforce_clearance": {"scope": ("within_layers", "between_layers", "both")},
    "remove_patches": {"keep": ("unselected", "union", "intersection", "difference")},
}


class _Alias(NamedTuple):
    """A filter parameter the core's option `core` takes, with the
    filter's default."""
    core: str
    default: Any
    doc: str


_ALIASES: Dict[str, Dict[str, _Alias]] = {
    "intersect_and_split": {
        "split_self_intersections": _Alias("self", False, "the filter's name of self"),
        "weld_duplicate_vertices": _Alias(
            "weld_duplicates", False, "the filter's name of weld_duplicates"),
    },
    "remove_self_intersections": {
        "removed_to_layer": _Alias("keep_removed", False, "the filter's name of keep_removed"),
    },
    "remove_patches": {
        "removed_to_layer": _Alias("removed_mesh", False, "the filter's name of removed_mesh"),
    },
    "paint_patches": {
        "crease_angle": _Alias("crease_angle_deg", 0.0, "the filter's name of crease_angle_deg"),
    },
}

# The filter's defaults where the core's option has another: the module's
# defaults give what the filter's give.
_DEFAULTS: Dict[str, Dict[str, Any]] = {
    "inspect": {"self_intersections": True},
    "intersect_and_split": {"remove_duplicate_faces": True},
    "fill_holes": {"max_diameter": 0.5},
    "measure_clearance": {"tau": "1%", "scope": "within_layers"},
    "enforce_clearance": {"tau": "1%", "scope": "within_layers", "max_displacement": "0%"},
    "remove_patches": {"keep": "union"},
}

# Options that are distances: mesh units, or a percentage of the diagonal
# of the bounding box of all the meshes given.
_DISTANCES: Dict[str, Tuple[str, ...]] = {
    "measure_clearance": ("tau",),
    "enforce_clearance": ("tau", "max_displacement"),
}


_VERTEX_ARGUMENTS = ("vertices", "vertices1", "vertices2")


def _diagonal(arguments) -> float:
    """The diagonal of the bounding box of the vertex arrays given (1 where
    there are none, as the filter's for an empty document)."""
    lo = hi = None
    for value in arguments:
        a = np.asarray(value, dtype=float) if value is not None else None
        if a is None or a.ndim != 2 or a.shape[1:] != (3,) or not len(a):
            continue
        lo = a.min(axis=0) if lo is None else np.minimum(lo, a.min(axis=0))
        hi = a.max(axis=0) if hi is None else np.maximum(hi, a.max(axis=0))
    return 1.0 if lo is None else float(np.linalg.norm(hi - lo))


def _distance(name: str, value, arguments):
    if not isinstance(value, str):
        return value
    text = value.strip()
    try:
        if not text.endswith("%"):
            raise ValueError
        percent = float(text[:-1])
    except ValueError:
        raise InvalidInputError(
            f"{name} must be a distance in mesh units or a percentage of the bounding box "
            f"diagonal such as '1%' (got {value!r})") from None
    return percent / 100 * _diagonal(arguments)


def _translate(core_name: str, function_name: str, arguments, options: Dict[str, Any]) -> None:
    """The filter-named options turned into the core's, in place."""
    for name, alias in _ALIASES.get(core_name, {}).items():
        if name in options:
            if alias.core in options:
                raise TypeError(f"{function_name}() got both {name} and {alias.core} (the same "
                                f"option)")
            options[alias.core] = options.pop(name)
    for name, value in _DEFAULTS.get(core_name, {}).items():
        if not (core_name == "remove_patches" and name == "keep" and "remove" in options):
            options.setdefault(name, value)  # (patch ids to remove leave keep unset)
    for name, choices in FILTER_CHOICES.get(core_name, {}).items():
        value = options.get(name)
        if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            if not 0 <= value < len(choices):
                raise InvalidInputError(
                    f"{name} must be one of {', '.join(map(repr, choices))} or their index 0 to "
                    f"{len(choices) - 1} (got {value})")
            options[name] = choices[value]
    for name in _DISTANCES.get(core_name, ()):
        if name in options:
            options[name] = _distance(name, options[name], arguments)


def _write_report(path, result) -> None:
    report = result if isinstance(result, dict) else getattr(result, "report", None)
    with open(path, "w") as f:
        json.dump(report, f, indent=1, default=_json_value)
        f.write("\n")


def _json_value(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON")


def _with_options(core_name: str, exclude: Tuple[str, ...] = ()):
    """Gives a function the keyword options of the core function `core_name`
    (names, defaults and descriptions from _core.OPTIONS, with the filter's
    names and defaults where they differ), report_file and progress, in its
    signature and docstring; the call translates the filter's names and
    values to the core's and writes the report where report_file says."""

    def decorate(function):
        signature = _inspect.signature(function)
        fixed = [p for p in signature.parameters.values() if p.kind != p.VAR_KEYWORD]
        taken = {p.name for p in fixed}
        defaults = _DEFAULTS.get(core_name, {})
        options = [(name, defaults.get(name, default), doc)
                   for name, default, doc in _core.OPTIONS[core_name]
                   if name not in exclude and name not in taken]
        options += [(name, alias.default, alias.doc)
                    for name, alias in _ALIASES.get(core_name, {}).items()
                    if alias.core not in exclude]
        options.append(("report_file", "", "when not empty, the report is also written to this "
                                           "path as one JSON object (as the filter's)"))
        parameters = fixed + [
            _inspect.Parameter(name, _inspect.Parameter.KEYWORD_ONLY, default=default)
            for name, default, _ in options
        ]
        parameters.append(
            _inspect.Parameter("progress", _inspect.Parameter.KEYWORD_ONLY, default=None))

        @functools.wraps(function)
        def call(*args, **kwargs):
            report_file = kwargs.pop("report_file", "")
            for name in exclude:
                if name in kwargs:
                    raise TypeError(f"{function.__name__}() sets {name} itself")
            given = signature.bind_partial(*args, **kwargs).arguments
            vertices = [given[n] for n in _VERTEX_ARGUMENTS if n in given]
            _translate(core_name, function.__name__, vertices, kwargs)
            result = function(*args, **kwargs)
            if report_file:
                _write_report(report_file, result)
            return result

        call.__signature__ = signature.replace(parameters=parameters)
        lines = [f"    {name} = {default!r}: {doc}" for name, default, doc in options]
        lines.append("    progress = None: callable(percent, stage); returning False stops")
        call.__doc__ = (function.__doc__ or "").rstrip() + "\n\n    Options:\n" + "\n".join(lines)
        return call

    return decorate


def _pairs(meshes) -> List[Arrays]:
    return [tuple(mesh) for mesh in meshes]


# ---------------------------------------------------------------- inspection


def set_threads(count: int) -> None:
    """Sets how many threads MeshMend's functions use from now on; 0 goes
    back to the default: the environment variable MESHMEND_THREADS (read
    once, when MeshMend first runs something), else every CPU the process
    may run on. Call it between calls, not while one runs in another thread."""
    _core.set_threads(int(count))


def threads() -> int:
    """How many threads MeshMend's functions use."""
    return _core.threads()


@_with_options("inspect")
def inspect(vertices, faces, **options) -> Dict[str, Any]:
    """Defect counts with the keys and definitions of the checker meshcheck
    (vertices, faces, border_edges, non_manifold_edges, is_closed, volume,
    genus, ...; self_intersecting_pairs unless self_intersections=False),
    and whether float can hold the detail (float_steps_in_shortest_edge,
    precision_note).
    Non-finite coordinates are counted (non_finite_vertices), not refused."""
    return _core.inspect(vertices, faces, **options)


def count_self_intersections(vertices, faces) -> int:
    """Number of self-intersecting face pairs, exactly (the rule of CGAL's
    self_intersections: faces sharing a vertex or an edge count only when
    they meet beyond it)."""
    return _core.count_self_intersections(vertices, faces)


@_with_options("find_intersections")
def find_intersections(vertices1, faces1, vertices2=None, faces2=None, **options) -> FindResult:
    """Intersecting face pairs of one mesh (self) or of two (self and cross).
    pairs rows are (mesh_a, face_a, mesh_b, face_b), meshes numbered from 0."""
    meshes = [(vertices1, faces1)]
    if vertices2 is not None or faces2 is not None:
        meshes.append((vertices2, faces2))
    return FindResult(*_core.find_intersections(meshes, **options))


# ---------------------------------------------------------------- intersect and split


def _split(meshes, options) -> SplitResult:
    out = _core.intersect_and_split(meshes, **options)
    return SplitResult(
        meshes=_pairs(out["meshes"]), curve_edges=list(out["curve_edges"]),
        merged=tuple(out["merged"]), merged_curve_edges=out["merged_curve_edges"],
        merged_part=out["merged_part"], report=out["report"])


@_with_options("intersect_and_split")
def intersect_and_split(vertices1, faces1, vertices2, faces2, **options) -> SplitResult:
    """Inserts the exact intersection curves of two meshes into both: only
    crossed faces are re-triangulated, every other face stays as it was.
    report['remaining_intersecting_pairs'] (verify=True) counts the pairs
    still intersecting in `merged` (faces meeting only along a shared curve
    edge or vertex do not count). The output is exact to double; a float
    file (STL, most PLY) rounds it, and rounding to nearest can make faces
    that meet along a curve cross: round_to_float=True rounds it the way
    that keeps them apart (as the MeshLab filter does) and checks the float
    result. Where curve points lie a few float steps apart, no rounding
    keeps every face apart: without snap_tolerance, the split with
    snap_tolerance=0.05 (which merges such points) is tried too and kept if
    it leaves fewer (report['quality_snapped_for_float']); the report counts
    what remains."""
    return _split([(vertices1, faces1), (vertices2, faces2)], options)


@_with_options("intersect_and_split")
def intersect_and_split_meshes(meshes, **options) -> SplitResult:
    """intersect_and_split for any number of meshes, given as a list of
    (vertices, faces) pairs."""
    return _split(list(meshes), options)


@_with_options("intersect_and_split", exclude=("between_meshes", "self"))
def split_self_intersections(vertices, faces, **options) -> SplitResult:
    """Inserts a mesh's own self-intersection curves into it (the 'within
    the current layer' mode of Intersect and Split Layers)."""
    for name in ("between_meshes", "self"):
        if name in options:
            raise TypeError(f"split_self_intersections() sets {name} itself")
    return _split([(vertices, faces)], dict(options, between_meshes=False, self=True))


@_with_options("remove_self_intersections")
def remove_self_intersections(vertices, faces, **options) -> SelfIntersectionResult:
    """Keeps the part of a consistently oriented mesh that is outside with
    respect to its orientation (TransforMesh): cut along the exact
    self-intersection curves, grown from seed faces, stitched manifold."""
    out = _core.remove_self_intersections(vertices, faces, **options)
    removed = out["removed"]
    return SelfIntersectionResult(*out["mesh"], out["face_origin"],
                                  None if removed is None else tuple(removed), out["report"])


# ---------------------------------------------------------------- holes, trimming, stitching


@_with_options("fill_holes")
def fill_holes(vertices, faces, **options) -> FillHolesResult:
    """Closes the holes with patches that follow the surface around them
    (advancing front, then a Poisson solve with learned Laplacians). A hole
    whose patch would intersect falls back to a flatter shape or stays open,
    with its reason in report['holes']."""
    out = _core.fill_holes(vertices, faces, **options)
    return FillHolesResult(*out["mesh"], out["new_faces"], out["new_vertices"], out["report"])


@_with_options("trim_along_loop")
def trim_along_loop(vertices, faces, **options) -> TrimResult:
    """Removes the faces on one side of a closed loop of vertices (loop,
    picked_vertices or selected_vertices), keeping the side of keep_face
    (or the left of the loop's direction). No vertex is added or moved."""
    out = _core.trim_along_loop(vertices, faces, **options)
    return TrimResult(*out["mesh"], out["vertex_index"], out["loop"], tuple(out["removed"]),
                      out["report"])


@_with_options("stitch_boundaries")
def stitch_boundaries(vertices, faces, a, b, **options) -> StitchResult:
    """Joins border paths a and b (vertex indices in order along a border)
    with a strip of faces oriented like the faces they join. For two meshes,
    concatenate them first (offset the second's indices by len(vertices1))."""
    out = _core.stitch_boundaries(vertices, faces, a, b, **options)
    return StitchResult(*out["mesh"], out["new_faces"], out["new_vertices"], out["report"])


@_with_options("stitch_sequence")
def stitch_sequence(vertices, faces, paths, pairs=None, **options) -> StitchResult:
    """Stitches border paths pairwise in the order of `pairs` (default
    (0, 1), (2, 3), ...), concatenating the leftovers at junctions so that a
    later stitch covers them."""
    out = _core.stitch_sequence(vertices, faces, paths, pairs, **options)
    return StitchResult(*out["mesh"], out["new_faces"], out["new_vertices"], out["report"])


def border_paths(vertices, faces, selected_vertices) -> List[Tuple[Any, bool]]:
    """The runs of selected border vertices (a mask or indices) along the
    borders, as [(vertex indices in the border's direction, closed)]."""
    return [(path, bool(closed))
            for path, closed in _core.border_paths(vertices, faces, selected_vertices)]


@_with_options("close_gaps")
def close_gaps(vertices, faces, **options) -> CloseGapsResult:
    """Merges border edges whose ends coincide within merge_tolerance, then
    stitches borders facing each other within max_gap, never making an edge
    non-manifold or breaking the orientation."""
    out = _core.close_gaps(vertices, faces, **options)
    return CloseGapsResult(*out["mesh"], out["vertex_index"], out["report"])


# ---------------------------------------------------------------- clearance


def _meshes(vertices, faces, vertices2, faces2) -> List[Arrays]:
    meshes = [(vertices, faces)]
    if vertices2 is not None or faces2 is not None:
        meshes.append((vertices2, faces2))
    return meshes


@_with_options("measure_clearance")
def measure_clearance(vertices, faces, vertices2=None, faces2=None,
                      **options) -> MeasureClearanceResult:
    """The smallest distance between faces sharing no vertex, within a mesh
    and (with a second mesh) between the two; per-vertex local clearances,
    the faces closer than tau and a histogram."""
    out = _core.measure_clearance(_meshes(vertices, faces, vertices2, faces2), **options)
    return MeasureClearanceResult(list(out["vertex_clearance"]), list(out["faces_below_tau"]),
                                  out["report"])


@_with_options("enforce_clearance")
def enforce_clearance(vertices, faces, vertices2=None, faces2=None,
                      **options) -> EnforceClearanceResult:
    """Moves vertices as little as possible until every face pair in scope
    is at least tau apart (Gauss-Newton steps, a line search that never lets
    the surfaces cross). Faces are never changed. When locked vertices, the
    cap or the shape stop it short, report['reached'] is False and
    report['stop_reason'] says why."""
    out = _core.enforce_clearance(_meshes(vertices, faces, vertices2, faces2), **options)
    return EnforceClearanceResult(_pairs(out["meshes"]), out["report"])


# ---------------------------------------------------------------- patches


@_with_options("paint_patches")
def paint_patches(vertices, faces, **options) -> PaintResult:
    """Flood-fills the faces into patches bounded by the intersection curves,
    borders and non-manifold edges, and classifies each against every part
    with generalized winding numbers (report['patch_list'])."""
    out = _core.paint_patches(vertices, faces, **options)
    return PaintResult(out["patch_of_face"], out["report"])


@_with_options("remove_patches")
def remove_patches(vertices, faces, **options) -> PatchesResult:
    """Removes the patches `remove` (ids), or keeps a boolean result
    (keep='union', the default, 'intersection' or 'difference'), and welds
    what is left. removed_mesh=True also returns the removed patches."""
    if options.get("keep") == "unselected":  # the filter's first choice: the ids in remove
        options["keep"] = None
    out = _core.remove_patches(vertices, faces, **options)
    removed = out["removed"]
    return PatchesResult(*out["mesh"], out["face_origin"], out["report"],
                         None if removed is None else tuple(removed))


@_with_options("select_patches")
def select_patches(vertices, faces, by=1, ids="", part=1, **options) -> SelectPatchesResult:
    """Chooses patches as the Select Patches filter does (`by`, in its
    order): 0 the ids in `ids` ("0, 3, 5-7"), 1 those with a face in
    selected_faces, 2 outside every other part, 3 inside every other part,
    4 inside part `part`, 5 not on the outer surface of the union."""
    out = _core.select_patches(vertices, faces, by, ids, part, **options)
    return SelectPatchesResult(out["selected_faces"], out["patch_of_face"], out["report"])


@_with_options("intersect_and_split", exclude=("separate_meshes", "overlaps_once"))
def boolean(vertices1, faces1, vertices2, faces2, operation="union", **options) -> PatchesResult:
    """The union, intersection or difference (first minus second) of two
    closed meshes: intersect_and_split (merged; its options), then
    remove_patches(keep=operation). report['split'] holds the split's report.
    Meshes that intersect themselves need self=True (scans: also
    weld_duplicates=True, remove_duplicate_faces=True)."""
    for name in ("separate_meshes", "overlaps_once"):
        if name in options:  # the classification needs both sides of a planar overlap
            raise TypeError(f"boolean() sets {name} itself")
    split = intersect_and_split(vertices1, faces1, vertices2, faces2,
                                **dict(options, separate_meshes=False))
    merged_vertices, merged_faces = split.merged
    result = remove_patches(merged_vertices, merged_faces, part=split.merged_part,
                            curve_edges=split.merged_curve_edges, keep=operation,
                            round_to_float=options.get("round_to_float", False),
                            progress=options.get("progress"))
    result.report["split"] = split.report
    return result


# ---------------------------------------------------------------- files and other libraries


def read_mesh(path) -> Arrays:
    """(vertices, faces) of an OFF, PLY, STL or OBJ file, vertices as stored
    (an STL has three per facet), polygons fan-triangulated."""
    return tuple(_core.read_mesh(os.fspath(path)))


def write_mesh(path, vertices, faces) -> None:
    """Writes OFF or binary PLY (by the extension), coordinates in double."""
    _core.write_mesh(os.fspath(path), vertices, faces)


def as_arrays(mesh) -> Arrays:
    """(vertices, faces) arrays of a pymeshlab.Mesh, of a trimesh-style object
    (.vertices, .faces) or of a (vertices, faces) pair; dtypes as given (every
    function checks them)."""
    if hasattr(mesh, "vertex_matrix") and hasattr(mesh, "face_matrix"):
        return from_pymeshlab(mesh)
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return np.asarray(mesh.vertices), np.asarray(mesh.faces)
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        return np.asarray(mesh[0]), np.asarray(mesh[1])
    raise TypeError(
        f"as_arrays() takes a pymeshlab.Mesh, an object with .vertices and .faces (trimesh) or a "
        f"(vertices, faces) pair, not {type(mesh).__name__}")


def from_pymeshlab(mesh) -> Arrays:
    """(vertices, faces) of a pymeshlab.Mesh (vertex_matrix(), face_matrix())."""
    return (np.array(mesh.vertex_matrix(), dtype=np.float64),
            np.array(mesh.face_matrix(), dtype=np.int32))


def to_pymeshlab(vertices, faces):
    """A pymeshlab.Mesh of the arrays (needs pymeshlab)."""
    try:
        import pymeshlab
    except ImportError as e:
        raise ImportError("to_pymeshlab needs pymeshlab (pip install pymeshlab)") from e
    return pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(vertices, dtype=np.float64),
                          face_matrix=np.ascontiguousarray(faces, dtype=np.int32))


def to_trimesh(vertices, faces):
    """A trimesh.Trimesh of the arrays, taken as they are (process=False; needs trimesh)."""
    try:
        import trimesh
    except ImportError as e:
        raise ImportError("to_trimesh needs trimesh (pip install trimesh)") from e
    return trimesh.Trimesh(vertices=np.asarray(vertices, dtype=np.float64),
                           faces=np.asarray(faces), process=False)


__all__ = [
    "Error", "InvalidInputError", "TopologyError", "CancelledError", "FACE_DEFECTS",
    "VERTEX_DEFECTS", "set_threads", "threads", "inspect", "count_self_intersections",
    "find_intersections",
    "intersect_and_split", "intersect_and_split_meshes", "split_self_intersections",
    "remove_self_intersections", "fill_holes", "trim_along_loop", "stitch_boundaries",
    "stitch_sequence", "border_paths", "close_gaps", "measure_clearance", "enforce_clearance",
    "paint_patches", "remove_patches", "select_patches", "boolean", "read_mesh", "write_mesh", "as_arrays",
    "from_pymeshlab", "to_pymeshlab", "to_trimesh",
]
