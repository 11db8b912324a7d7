#!/usr/bin/env python3
"""Runs MeshMend's benchmarks side by side with their peers, in the same run,
and rewrites the matching section of docs/BENCHMARKS.md.

    benchmarks/run.py intersections [--repeat N]
    benchmarks/run.py split [--repeat N]
    benchmarks/run.py selfintersect [--repeat N]
    benchmarks/run.py holes [--repeat N]        (needs numpy: /usr/bin/python3)
    benchmarks/run.py clearance [--repeat N]
    benchmarks/run.py stitch [--repeat N]
    benchmarks/run.py all --smoke

--smoke runs every benchmark once on its smallest inputs and writes the
tables to build/benchmarks-smoke.md instead of docs/BENCHMARKS.md: it proves
that the runners build, run and agree with their peers (it fails on a failed
or disagreeing method), and asserts no speed. The full test tier runs it.

Every benchmark takes --threads N: the threads MeshMend's runners use (it sets
MESHMEND_THREADS; 0, the default, leaves every CPU). The peers run on one
thread. The hole-filling comparison runs ours on 1 thread whatever it says,
and on every CPU beside it.

Needs scripts/setup to have run (the private MeshLab prefix) and ../shared
beside the project (the real meshes). Builds the C++ runners if needed."""
import argparse
import gzip
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_files import machine, write_off

ROOT = Path(__file__).resolve().parents[1]
BUILD = Path(os.environ.get("MESHMEND_BUILD_DIR", ROOT / "build"))
DATA = Path(os.environ.get("MESHMEND_SHARED_DIR", ROOT.parent / "shared")) / "data"
DOC = ROOT / "docs" / "BENCHMARKS.md"
SMOKE = False  # --smoke: the smallest inputs only, one run each
SKIPPED = 77  # exit status of a run that cannot start (CTest's SKIP_RETURN_CODE)


def smallest(items, keep=1):
    """Under --smoke the first `keep` items (each list is ordered smallest first)."""
    return items[:keep] if SMOKE else items


RUNNERS = ["bench_intersections", "bench_split", "bench_selfintersect", "filter_mend_intersect"]


def build_runners(targets=RUNNERS):
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(BUILD), "-DMESHMEND_BUILD_BENCHMARKS=ON"],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(BUILD), "-j", str(os.cpu_count() or 2),
                    "--target", *targets], check=True, stdout=subprocess.DEVNULL)


def data_file(name, tmp):
    path = DATA / name
    if path.exists():
        return path
    gz = DATA / (name + ".gz")
    if gz.exists():
        out = Path(tmp) / Path(name).name
        if not out.exists():
            with gzip.open(gz, "rb") as src, open(out, "wb") as dst:
                shutil.copyfileobj(src, dst)
        return out
    sys.exit(f"missing {path}: the benchmarks need ../shared/data")


def faces_of(path):
    with open(path, "rb") as f:
        for line in f:
            m = re.match(rb"element face (\d+)", line)
            if m:
                return int(m.group(1))
            if line.strip() == b"end_header":
                break
    return 0


def run_runner(args):
    out = subprocess.run([str(BUILD / "benchmarks" / "bench_intersections"), *map(str, args)],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def meshlabserver_ms(inputs, script_text, repeat):
    """Median wall time of scripts/meshlabserver running the script, minus the
    median of the same run with an empty script (loading and start-up)."""
    def timed(text):
        with tempfile.NamedTemporaryFile("w", suffix=".mlx", delete=False) as f:
            f.write(text)
        times = []
        for _ in range(repeat):
            cmd = [str(ROOT / "scripts" / "meshlabserver")]
            for i in inputs:
                cmd += ["-i", str(i)]
            t0 = time.perf_counter()
            proc = subprocess.run(cmd + ["-s", f.name], capture_output=True, text=True)
            times.append((time.perf_counter() - t0) * 1000)
            if proc.returncode != 0:
                raise RuntimeError(proc.stdout[-2000:])
        os.unlink(f.name)
        return statistics.median(times), proc.stdout
    base, _ = timed("<!DOCTYPE FilterScript>\n<FilterScript>\n</FilterScript>\n")
    total, log = timed(script_text)
    return max(0.0, total - base), log


BUILTIN = """<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Select Self Intersecting Faces"/>
</FilterScript>
"""


def threads_used():
    """What the tables say about threads: ours on MESHMEND_THREADS (as
    --threads sets it), else on every CPU; the peers on one."""
    n = os.environ.get("MESHMEND_THREADS")
    ours = f"{n} thread{'s' if n != '1' else ''} (`--threads {n}`)" if n else \
        f"every CPU ({os.cpu_count()} threads)"
    return f"MeshMend on {ours}, the peers on 1 thread"


def fmt(ms):
    return f"{ms:,.1f}" if ms < 100 else f"{ms:,.0f}"


def spot(key, text):
    """A value the README quotes (scripts/readme-numbers copies it there)."""
    return f"<!--n:{key}-->{text}<!--/n-->"


def intersections(repeat):
    tmp = tempfile.mkdtemp()
    sizes = [("res4", "bun_zipper_res4.ply", "dragon_vrip_res4.ply"),
             ("res3", "bun_zipper_res3.ply", "dragon_vrip_res3.ply"),
             ("res2", "bun_zipper_res2.ply", "dragon_vrip_res2.ply"),
             ("full", "bun_zipper.ply", "dragon_vrip.ply")]
    rows, scaling, meshlab_rows = [], [], []
    for label, bunny, dragon in smallest(sizes):
        a, b = data_file("stanford/" + bunny, tmp), data_file("stanford/" + dragon, tmp)
        fa, fb = faces_of(a), faces_of(b)
        print(f"bunny + dragon {label}: {fa:,} + {fb:,} faces", file=sys.stderr)
        result = run_runner(["--repeat", repeat, a, b])
        by = {m["method"]: m for m in result["methods"]}
        rows.append((label, fa, fb, by))
        scaling.append((fa + fb, by))
    # MeshLab's built-in filter against ours, both through meshlabserver.
    ours_script = (ROOT / "samples" / "select_intersecting.mlx").read_text()
    for name in smallest(["stanford/dragon_vrip_res2.ply", "stanford/dragon_vrip.ply"]):
        path = data_file(name, tmp)
        builtin_ms, _ = meshlabserver_ms([path], BUILTIN, 1 if SMOKE else 3)
        ours_ms, log = meshlabserver_ms([path], ours_script, 1 if SMOKE else 3)
        m = re.search(r"has (\d+) self-intersecting pairs \((\d+) faces\)", log)
        meshlab_rows.append((Path(name).name, faces_of(path), ours_ms, builtin_ms, m.group(2) if m else "?"))
    shutil.rmtree(tmp)

    def cell(m, key="median_ms"):
        return fmt(m[key]) if m.get("ok") else "failed: " + m.get("error", "?")

    out = [f"Measured on {machine()}, {time.strftime('%Y-%m-%d')}, {threads_used()}; each "
           "number is the median of "
           f"{repeat} runs in a child process of one `bench_intersections` run (`benchmarks/run.py "
           f"intersections`), so ours and the peers ran on the same input in the same run. Times "
           f"exclude file reading. Peak memory is the child's peak resident set (inputs included).",
           "",
           "**Cross-intersections (bunny + dragon, as stored).** Ours: `findIntersections` between the two "
           "meshes. CGAL: `box_intersection_d` on the face boxes + exact `do_intersect` (Epick), the way "
           "CGAL users find pairs between two meshes. Alternative: ours with median-split hierarchies "
           "(no hashed grid between the meshes, no Morton-order hierarchy within each).",
           "",
           "| input | faces | pairs | ours ms | CGAL ms | CGAL / ours | median-split layout ms | ours peak MB | CGAL peak MB |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for label, fa, fb, by in rows:
        o, c, alt = by["meshmend_cross"], by["cgal_box_intersection_d_cross"], by["meshmend_cross_median_layout"]
        ratio = f"{c['median_ms'] / o['median_ms']:.1f}×" if o.get("ok") and c.get("ok") else "–"
        agree = "" if not c.get("ok") or c["result"] == o["result"] else " (differ!)"
        ours = cell(o)
        if label == "full":
            ours, ratio = spot("cross_bunny_dragon_ms", ours), spot("cross_bunny_dragon_ratio", ratio)
        out.append(f"| bunny + dragon {label} | {fa:,} + {fb:,} | {o['result']:,}{agree} | {ours} | {cell(c)} | "
                   f"{ratio} | {cell(alt)} | {o.get('peak_rss_mb', 0):.0f} | {c.get('peak_rss_mb', 0):.0f} |")
    out += ["",
            "**All intersections of the two joined into one mesh** (each mesh's self-intersections and "
            "the pairs between them: the same job for everyone). CGAL: `PMP::self_intersections` on a "
            "`Surface_mesh`; the lower resolutions have non-manifold edges, which a `Surface_mesh` "
            "refuses, so there CGAL runs `box_self_intersection_d` with the same rule and its exact "
            "predicates (as `meshcheck` does).",
            "",
            "| input | faces | pairs | ours ms | CGAL ms | CGAL / ours | median-split layout ms | ours peak MB | CGAL peak MB |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for label, fa, fb, by in rows:
        o, c = by["meshmend_self_joined"], by["cgal_self_intersections_joined"]
        alt = by["meshmend_self_joined_median_layout"]
        ratio = f"{c['median_ms'] / o['median_ms']:.1f}×" if o.get("ok") and c.get("ok") else "–"
        agree = "" if not c.get("ok") or c["result"] == o["result"] else " (differ!)"
        out.append(f"| bunny + dragon {label} | {fa + fb:,} | {o['result']:,}{agree} | {cell(o)} | {cell(c)} | "
                   f"{ratio} | {cell(alt)} | {o.get('peak_rss_mb', 0):.0f} | {c.get('peak_rss_mb', 0):.0f} |")
    out += ["",
            "**Scaling** (the four resolutions above): milliseconds per million input faces; flat means linear.",
            "",
            "| faces | cross: ours | joined: ours | joined: CGAL |",
            "|---:|---:|---:|---:|"]
    for faces, by in scaling:
        def per(m):
            return f"{m['median_ms'] / (faces / 1e6):,.0f}" if m.get("ok") else "–"
        out.append(f"| {faces:,} | {per(by['meshmend_cross'])} | {per(by['meshmend_self_joined'])} | "
                   f"{per(by['cgal_self_intersections_joined'])} |")
    out += ["",
            "**Through meshlabserver**: MeshLab 2020.09's built-in *Select Self Intersecting Faces* "
            "against *MeshMend: Select Intersecting Faces* (mode: within the current layer), each the "
            "median of 3 `scripts/meshlabserver` runs minus the median of 3 runs with an empty script "
            "(start-up and loading).",
            "",
            "| mesh | faces | ours ms | MeshLab built-in ms | built-in / ours | faces selected (ours) |",
            "|---|---:|---:|---:|---:|---:|"]
    for name, faces, ours_ms, builtin_ms, selected in meshlab_rows:
        out.append(f"| {name} | {faces:,} | {fmt(ours_ms)} | {fmt(builtin_ms)} | "
                   f"{builtin_ms / max(ours_ms, 1e-9):.1f}× | {selected} |")
    return "\n".join(out)


def uv_sphere_arrays(centre, radius, rings, segments):
    """A closed UV sphere (two poles, rings x segments quads split in two):
    points and faces."""
    import math
    points = [(centre[0], centre[1], centre[2] + radius)]
    for i in range(1, rings):
        theta = math.pi * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            points.append((centre[0] + radius * math.sin(theta) * math.cos(phi),
                           centre[1] + radius * math.sin(theta) * math.sin(phi),
                           centre[2] + radius * math.cos(theta)))
    points.append((centre[0], centre[1], centre[2] - radius))
    south = len(points) - 1
    ring = lambda i, j: 1 + (i - 1) * segments + j % segments
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        for j in range(segments):
            a, b, c, d = ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1)
            faces += [(a, c, b), (b, c, d)]
    faces += [(ring(rings - 1, j), south, ring(rings - 1, j + 1)) for j in range(segments)]
    return points, faces


def uv_sphere(path, centre, radius, rings, segments):
    """A closed UV sphere in an OFF file."""
    return write_off(path, *uv_sphere_arrays(centre, radius, rings, segments))


def split_rounds(command, rounds):
    """Runs a bench_split command `rounds` times, ours and the peers one
    after the other in each round, and keeps per method the median of the
    rounds' medians: a burst of load on this shared machine then spoils one
    round, not the comparison."""
    runs = [json.loads(subprocess.run(command, capture_output=True, text=True,
                                      check=True).stdout)["methods"] for _ in range(rounds)]
    methods = {}
    for name in [m["method"] for m in runs[0]]:
        entries = [m for run in runs for m in run if m["method"] == name]
        ok = [m for m in entries if m.get("ok")]
        if len(ok) < len(entries):
            methods[name] = next(m for m in entries if not m.get("ok"))
            continue
        merged = dict(ok[0])
        merged["median_ms"] = statistics.median(m["median_ms"] for m in ok)
        merged["round_medians_ms"] = [m["median_ms"] for m in ok]
        merged["peak_rss_mb"] = max(m.get("peak_rss_mb", 0) for m in ok)
        merged["page_faults_per_run"] = statistics.median(m.get("page_faults_per_run", 0)
                                                          for m in ok)
        methods[name] = merged
    return methods


def split(repeat, rounds=3):
    import tempfile
    tmp = tempfile.mkdtemp(prefix="meshmend-bench-")
    rows = [("blobby + eight", DATA / "pairs/blobby.off", DATA / "pairs/eight.off", [])]
    if SMOKE:
        return split_table(rows, repeat, 1, tmp)
    small = uv_sphere(Path(tmp) / "sphere_70k.off", (0, 0, 0), 1.0, 141, 250)
    large = uv_sphere(Path(tmp) / "sphere_870k.off", (0.37, 0.21, 0.13), 1.0, 484, 900)
    rows += [("ballA + ballB", DATA / "pairs/ballA.off", DATA / "pairs/ballB.off", []),
             ("cheburashka + decimated-knight", DATA / "pairs/cheburashka.off",
              DATA / "pairs/decimated-knight.off", []),
             ("generated spheres, 70k + 870k faces", small, large, []),
             ("bunny + dragon (sample configuration)", DATA / "stanford/bun_zipper.ply",
              data_file("stanford/dragon_vrip.ply", tmp), ["--sample", "--autorefine", "--limit", "300"])]
    return split_table(rows, repeat, rounds, tmp)


def split_table(rows, repeat, rounds, tmp):
    out = [f"Measured on {machine()}, {time.strftime('%Y-%m-%d')}, {threads_used()}; per "
           "method the median of "
           f"{rounds} rounds, each the median of {repeat} runs in one `bench_split` run per pair "
           "(`benchmarks/run.py split`; in each round ours and the peers run one after the other, "
           "each method in a child process). "
           "Ours: `splitAlongIntersections` with `merged_output` off (the curves inserted into both "
           "meshes, the two refined meshes built: the job `PMP::corefine` does), and in the next "
           "column the default (the welded merged mesh built too). CGAL: `PMP::corefine` on two "
           "`Surface_mesh` copies (it refines in place; the copies are timed, as ours times "
           "reading its input into arrays), with its default parameters and with "
           "`throw_on_self_intersection(true)` (checked: it first searches both meshes for "
           "self-intersections near the curves); CGAL / ours compares ours with the faster of the "
           "two. The spheres are generated UV spheres crossing each other, at the sizes "
           "of the bunny and the dragon. On bunny + dragon ours runs the configuration of "
           "`samples/intersect_split.mlx` (seams welded, duplicate faces removed, the dragon's own "
           "self-intersections split too, merged output rounded to float: the filter's work); "
           "checked `PMP::corefine` refuses the pair (the dragon self-intersects; unchecked, "
           "its result is unspecified there), and CGAL's only "
           "alternative, `PMP::experimental::autorefine` of the two joined, runs under a "
           "5-minute limit. *Page faults* are those of the median run (memory the allocator "
           "handed back to the system after one run and took again in the next; about 11 µs "
           "each on this virtual machine). The *warm* columns run the same rounds with "
           "`--warm-allocator`: every method with glibc's malloc thresholds where its own "
           "dynamic rule leaves them once a process has freed a 32 MiB block (a host that has "
           "loaded and dropped a large mesh), so that no method's time includes memory faulted "
           "in again; the bunny + dragon rows run without it.",
           "",
           "| pair | faces split (ours) | ours ms | ours + merged ms | ours peak MB | "
           "CGAL ms | CGAL checked ms | CGAL peak MB | CGAL / ours | page faults ours / CGAL | "
           "warm: ours ms | warm: CGAL ms | warm: CGAL / ours |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def cell(m):
        if m is None:
            return "–"
        return fmt(m["median_ms"]) if m.get("ok") else m.get("error", "?").strip()

    def ours_and_best_peer(methods):
        o = methods.get("meshmend_split_refine") or methods["meshmend_split_sample"]
        peers = [c for c in (methods.get("cgal_corefine"), methods.get("cgal_corefine_checked"))
                 if c and c.get("ok")]
        best = min(peers, key=lambda c: c["median_ms"]) if peers else None
        ratio = f"{best['median_ms'] / o['median_ms']:.1f}×" if best and o.get("ok") else "–"
        return o, best, ratio

    def faults(m):
        return f"{m['page_faults_per_run']:.0f}" if m and m.get("ok") else "–"

    for name, a, b, extra in rows:
        command = [str(BUILD / "benchmarks" / "bench_split"), "--repeat", str(repeat), *extra,
                   str(a), str(b)]
        methods = split_rounds(command, rounds)
        o, best, ratio = ours_and_best_peer(methods)
        merged = methods.get("meshmend_split")
        plain, checked = methods.get("cgal_corefine"), methods.get("cgal_corefine_checked")
        peak = max((c.get("peak_rss_mb", 0) for c in (plain, checked) if c), default=0)
        warm = ["–", "–", "–"]
        if "--sample" not in extra:
            wo, wbest, wratio = ours_and_best_peer(
                split_rounds(command[:1] + ["--warm-allocator"] + command[1:], rounds))
            warm = [cell(wo), cell(wbest), wratio]
        out.append(f"| {name} (corefine) | {o.get('result', '–')} | {cell(o)} | {cell(merged)} | "
                   f"{o.get('peak_rss_mb', 0):.0f} | {cell(plain)} | {cell(checked)} | "
                   f"{peak:.0f} | {ratio} | {faults(o)} / {faults(best)} | {' | '.join(warm)} |")
        auto = methods.get("cgal_autorefine")
        if auto:
            ratio = (f"{auto['median_ms'] / o['median_ms']:.1f}×"
                     if auto.get("ok") and o.get("ok") else "–")
            out.append(f"| {name} (autorefine) | {o.get('result', '–')} | {cell(o)} | – | "
                       f"{o.get('peak_rss_mb', 0):.0f} | {cell(auto)} | – | "
                       f"{auto.get('peak_rss_mb', 0):.0f} | {ratio} | {faults(o)} / "
                       f"{faults(auto)} | – | – | – |")
    return "\n".join(out)


def two_spheres(path):
    """Two unit UV spheres (100 rings x 126 segments, 24,948 faces each) in one
    mesh, their centres 1.98 apart: a shallow lens of overlap whose boundary
    circle (radius 0.14) crosses about 100 pairs of faces."""
    a_points, a_faces = uv_sphere_arrays((0, 0, 0), 1.0, 100, 126)
    b_points, b_faces = uv_sphere_arrays((1.98, 0.031, 0.017), 1.0, 100, 126)
    n = len(a_points)
    return write_off(path, a_points + b_points,
                     a_faces + [(a + n, b + n, c + n) for a, b, c in b_faces])


SELFINTERSECT_PEERS = ["cgal_remove_self_intersections",
                       "cgal_autorefine_and_remove_self_intersections"]


def selfintersect(repeat):
    tmp = tempfile.mkdtemp(prefix="meshmend-bench-")
    inputs = [("cow.off", data_file("self_intersecting/cow.off", tmp)),
              ("self_intersectA.obj", data_file("self_intersecting/self_intersectA.obj", tmp))]
    if not SMOKE:
        generated = two_spheres(Path(tmp) / "two_spheres_50k.off")
        inputs = [("generated: two overlapping spheres", generated), *inputs,
                  ("horse.ply", data_file("scanned/horse.ply", tmp)),
                  ("dragon_vrip_res4.ply", data_file("stanford/dragon_vrip_res4.ply", tmp)),
                  ("dragon_vrip_res3.ply", data_file("stanford/dragon_vrip_res3.ply", tmp)),
                  ("bun_zipper_res2.ply", data_file("stanford/bun_zipper_res2.ply", tmp))]
    limit = 60 if SMOKE else 600
    rows = []
    for name, path in inputs:
        print(name, file=sys.stderr)
        text = subprocess.run([str(BUILD / "benchmarks" / "bench_selfintersect"), "--repeat",
                               str(repeat), "--limit", str(limit), "--threads", "1", str(path)],
                              capture_output=True, text=True, check=True).stdout
        rows.append((name, json.loads(text)))
    shutil.rmtree(tmp)

    def succeeded(m, before):
        c = m.get("check")
        return bool(m.get("ok") and c and c["faces"] > 0 and c["remaining_pairs"] == 0
                    and c["manifold"] and (c["closed"] or not before["closed"]))

    def time_cell(m):
        if not m.get("ok"):
            error = m.get("error", "?").strip()
            return error if error.startswith(("crashed", "time limit", "skipped")) else f"threw “{error}”"
        return fmt(m["median_ms"]) + ("¹" if len(m["times_ms"]) == 1 and repeat > 1 else "")

    def peak_cell(m):
        """The timed runs' peak; none for a method that ran once (¹)."""
        if not m.get("ok") or (len(m["times_ms"]) == 1 and repeat > 1):
            return "–"
        return f"{m['peak_rss_mb']:.0f}"

    def result_cell(m, before):
        c = m.get("check")
        if not m.get("ok") or not c:
            return "–"
        shape = "closed" if c["closed"] else f"{c['border_edges']:,} border edges"
        if not c["manifold"]:
            shape += f", {c['non_manifold_edges']:,} nm edges, {c['non_manifold_vertices']:,} nm vertices"
        mark = "✓" if succeeded(m, before) else "✗"
        return f"{mark} {c['remaining_pairs']:,} left, {shape}, {c['components']} comp."

    skipped = [name for name, result in rows for m in result["methods"]
               if m.get("error", "").strip().startswith("skipped")]
    out = [f"Measured on {machine()}, {time.strftime('%Y-%m-%d')}, **ours and the peers on 1 "
           "thread** (`bench_selfintersect --threads 1`; CGAL's removal has no parallel code), and "
           f"ours also on every CPU ({os.cpu_count()} threads, *all CPUs*); medians of {repeat} runs "
           "in one `bench_selfintersect` run per input (`benchmarks/run.py selfintersect`), each "
           "method in a child process, so ours and the peers ran on the same input in the same "
           "run. Times exclude file reading; a method whose first run takes over 10 s runs once "
           f"(¹). Time limit {limit} s per method. *Peak MB*: the child's peak resident memory "
           "over the timed runs (its input and copies included; – where a method ran once).",
           "",
           "Ours: `removeSelfIntersections` with the options of the filter *MeshMend: Remove "
           "Self-Intersections* (defaults, result rounded to float as MeshLab stores it; its own "
           "verification of the result is included in the time). CGAL 5.5: "
           "`PMP::experimental::remove_self_intersections` (RSI: local smoothing and hole filling "
           "around the intersections) and `PMP::experimental::autorefine_and_remove_self_intersections` "
           "(ARSI: refine along the intersections, drop the inner patches, stitch; in "
           "`corefinement.h`, as 5.5 has no `autorefinement.h`), each on a `Surface_mesh` copy. "
           "Files with non-manifold edges (†), which a `Surface_mesh` refuses, reach CGAL through "
           "`repair_polygon_soup` + `orient_polygon_soup`, as a CGAL user would give them; the "
           "second splits the non-manifold edges apart, so CGAL starts from more crossing pairs "
           "(in brackets). ARSI requires a mesh without degenerate faces and is skipped otherwise "
           f"({', '.join(skipped) if skipped else 'no input here has one'}).",
           "",
           "Every result is checked independently, untimed: *left* counts the intersecting face "
           "pairs left, by CGAL's `PMP::self_intersections` (the soup rule of `meshcheck` where the "
           "result is not a polygon mesh); *closed* means no border or non-manifold edge, by vertex "
           "index; *comp.* counts connected components. ✓ = no pair left, edge- and "
           "vertex-manifold, and closed if the input was. *Pairs before* and *comp.* are the same "
           "counts on the file as stored (cow.off has one vertex stored twice, so its faces around "
           "that point count as crossing until the copies are welded, which ours does first). The "
           "ratios compare times where both methods succeeded. The generated mesh is two unit UV "
           "spheres (100 rings × 126 segments each) whose centres are 1.98 apart, in one mesh of "
           "49,896 faces: their shallow overlap is bounded by a circle of radius 0.14 that crosses "
           "about 100 face pairs, and the outer surface is the union of the two.",
           "",
           "| input | faces | comp. | pairs before | ours ms | ours peak MB | ours result | "
           "ours, all CPUs ms | RSI ms | RSI peak MB | RSI result | ARSI ms | ARSI peak MB | "
           "ARSI result | RSI / ours | ARSI / ours |",
           "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|---:|---:|---|---:|---:|"]
    for name, result in rows:
        before = result["input"]
        by = {m["method"]: m for m in result["methods"]}
        o = by["meshmend_remove_self_intersections"]
        repaired = [by[key] for key in SELFINTERSECT_PEERS if by[key].get("input_repaired")]
        pairs = f"{before['remaining_pairs']:,}"
        if repaired:
            pairs += f" ({repaired[0]['input_pairs']:,})"
        cells = [f"{name}{' †' if repaired else ''}", f"{before['faces']:,}",
                 str(before["components"]), pairs, time_cell(o), peak_cell(o),
                 result_cell(o, before), time_cell(by["meshmend_remove_self_intersections_all_cores"])]
        ratios = []
        for key in SELFINTERSECT_PEERS:
            c = by[key]
            cells += [time_cell(c), peak_cell(c), result_cell(c, before)]
            both = succeeded(o, before) and succeeded(c, before)
            ratios.append(f"{c['median_ms'] / o['median_ms']:.1f}×" if both else "–")
        out.append("| " + " | ".join(cells + ratios) + " |")
    if SMOKE:
        return "\n".join(out)
    before, o, every = next((r["input"], r["methods"][0], r["methods"][1]) for _, r in rows
                            if r["file"] == str(generated))
    met = succeeded(o, before) and o["median_ms"] < 100
    out += ["",
            "**Acceptance target** (issue 6): a 50k-face mesh with about 100 intersecting pairs "
            "repaired in under 100 ms. Measured on the generated mesh "
            f"({before['faces']:,} faces, {before['remaining_pairs']:,} pairs): {time_cell(o)} ms "
            f"on 1 thread, {'met' if met else 'not met'} ({time_cell(every)} ms on every CPU)."]
    rsi = next({m["method"]: m for m in r["methods"]}["cgal_remove_self_intersections"]
               for _, r in rows if r["file"] == str(generated))
    if succeeded(o, before) and succeeded(rsi, before):
        ratio = rsi["median_ms"] / o["median_ms"]
        out += ["",
                "**Against issue 43's target** (1 thread each): RSI / ours on the generated mesh "
                f"{ratio:.1f}× (target: at least 5×, {'met' if ratio >= 5 else 'not met'}); peak "
                f"memory ours {peak_cell(o)} MB, RSI {peak_cell(rsi)} MB."]
    return "\n".join(out)


def holes(repeat):
    """Hole filling: fidelity and speed (benchmarks/holes.py), with the
    measuring tools of ../shared/tools built beside the runners."""
    try:
        import holes as driver
    except ImportError as e:
        sys.exit(f"the holes benchmark needs numpy (Debian: python3-numpy): {e}")
    tools = BUILD / "shared-tools"
    subprocess.run(["cmake", "-S", str(ROOT.parent / "shared" / "tools"), "-B", str(tools),
                    "-DCMAKE_BUILD_TYPE=Release"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(tools), "-j", str(os.cpu_count() or 2), "--target",
                    "meshcheck", "peer_holefill"], check=True, stdout=subprocess.DEVNULL)
    return driver.section(BUILD, repeat, machine(), only="spot" if SMOKE else None)


def icosphere_arrays(centre, radius, levels):
    """A geodesic sphere: the icosahedron, each face cut in four `levels`
    times (20 * 4^levels nearly equal faces), projected on the sphere."""
    import math
    t = (1 + math.sqrt(5)) / 2
    points = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
              (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        middle = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                middle[key] = len(points)
                points.append(tuple((points[a][k] + points[b][k]) / 2 for k in range(3)))
            return middle[key]
        faces = [f for a, b, c in faces
                 for f in ((a, mid(a, b), mid(c, a)), (b, mid(b, c), mid(a, b)),
                           (c, mid(c, a), mid(b, c)), (mid(a, b), mid(b, c), mid(c, a)))]
    scaled = []
    for p in points:
        n = math.sqrt(sum(x * x for x in p))
        scaled.append(tuple(centre[k] + radius * p[k] / n for k in range(3)))
    return scaled, faces


def hollow_shell(path):
    """A hollow ball: an outer geodesic sphere (radius 1, 81,920 faces) and
    an inner one facing inwards (radius 0.95, 20,480 faces) moved 0.0445
    towards +x, so the shell is 0.0055 thin on that side."""
    outer_points, outer_faces = icosphere_arrays((0, 0, 0), 1.0, 6)
    inner_points, inner_faces = icosphere_arrays((0.0445, 0, 0), 0.95, 5)
    n = len(outer_points)
    return write_off(path, outer_points + inner_points,
                     outer_faces + [(a + n, c + n, b + n) for a, b, c in inner_faces])


def clearance(repeat):
    tmp = tempfile.mkdtemp(prefix="meshmend-bench-")
    shell = hollow_shell(Path(tmp) / "hollow_shell_100k.off")
    tau = 0.006
    text = subprocess.run([str(BUILD / "benchmarks" / "bench_clearance"), "--repeat", str(repeat),
                           "--tau", str(tau), str(shell)], capture_output=True, text=True,
                          check=True).stdout
    r = json.loads(text)
    enforce, detect = r["methods"]
    o = r["outcome"]
    target = 2000
    verdict = "met" if enforce.get("ok") and enforce["median_ms"] < target else "not met"
    return "\n".join([
        f"Measured on {machine()}, {time.strftime('%Y-%m-%d')}; medians of {repeat} runs in one "
        "`bench_clearance` run (`benchmarks/run.py clearance`), each in a child process. No peer "
        "library enforces a minimum clearance (CGAL has none; Blender's minimum thickness is a "
        "stub), so ours is measured alone: `enforceClearance` within the layer, rounded to float "
        "(the filter's configuration), and `measureClearance`, the detection it repeats. Input: "
        f"a hollow ball, {r['faces']:,} faces in one mesh (an outer geodesic sphere of radius 1 "
        "and an inner one of radius 0.95 facing inwards, moved 0.0445 towards +x: the shell is "
        f"0.0055 thin there), tau = {tau}.",
        "",
        "| method | ms | peak MB | violating pairs (enforce: left; measure: found) |",
        "|---|---:|---:|---:|",
        *[f"| {m['method']} | {fmt(m['median_ms']) if m.get('ok') else m.get('error')} | "
          f"{m.get('peak_rss_mb', 0):.0f} | {m.get('result', '–')} |" for m in (enforce, detect)],
        "",
        f"Outcome (one untimed run): minimum distance {o['min_distance_before']:.6g} → "
        f"{o['min_distance_after']:.6g}, violating pairs {o['violating_pairs_before']:,} → "
        f"{o['violating_pairs_after']:,}, largest displacement {o['max_displacement']:.4g} "
        f"(mean over moved vertices {o['mean_displacement']:.4g}), "
        f"{o.get('new_intersecting_pairs', 0)} intersecting pairs.",
        "",
        f"**Acceptance target** (issue 9): a 100k-face mesh with about 1,000 violating pairs "
        f"brought to tau in under 2 s: {fmt(enforce['median_ms'])} ms with "
        f"{o['violating_pairs_before']:,} violating pairs, {verdict}."])


STITCHING_FILES = ["ADIS16480.STL", "busted.STL", "cgaltest_deg_border.off",
                   "cgaltest_pinched.off", "conrod.stl", "quads_to_stitch.off"]


def stitch(repeat):
    """Stitching two border paths of 100k vertices each (ours alone: no peer
    stitches two paths across a gap), and Close Gaps Between Borders against
    CGAL's stitch_borders on the stitching corpus."""
    runner = str(BUILD / "benchmarks" / "bench_stitch")
    paths = 1000 if SMOKE else 100000
    r = json.loads(subprocess.run([runner, "--repeat", str(repeat), "--paths", str(paths)],
                                  capture_output=True, text=True, check=True).stdout)
    by = {m["method"]: m for m in r["methods"]}
    plain, checked = by["meshmend_stitch"], by["meshmend_stitch_checked"]
    load = os.getloadavg()[0]
    target = 50
    met = plain.get("ok") and plain["median_ms"] < target
    runs = {"meshmend_stitch": r["unchecked"], "meshmend_stitch_checked": r["checked"]}
    o = r["checked"]["outcome"]
    out = [f"Measured on {machine()}, {time.strftime('%Y-%m-%d')} (load average {load:.1f} after "
           f"the paths' runs: other programs shared the two cores); medians of {repeat} runs in one `bench_stitch` run per input "
           "(`benchmarks/run.py stitch`), each method in a child process, so ours and the peer "
           "ran on the same input in the same run.",
           "",
           f"**Two paths of {paths:,} vertices each** (`stitchPaths`, the core of *MeshMend: "
           "Stitch Boundaries*): two generated sheets of "
           f"{paths:,} × 3 vertices side by side ({r['faces']:,} faces, {r['vertices']:,} "
           "vertices in one mesh), three edge lengths apart, the second half a step along and "
           "waved (not coplanar); path a is the first sheet's last row, path b the second "
           "sheet's first row. Each run stitches its own copy of the mesh, made beforehand. No "
           "peer library does this (CGAL's `stitch_borders` only merges borders that already "
           "coincide, MeshLab has no such filter), so ours is measured alone, without and with "
           "the exact check of the new faces against the faces near the gap. The stitch counts "
           "the mesh's border edges (for its report) and makes a larger copy of the faces, with "
           "room for the new ones, on a second thread while it plans; *CPU* is the time one "
           "untimed run kept the calling thread and the whole process busy (on a loaded machine "
           "the wall time also waits for other programs).",
           "",
           "| method | ms | min ms | CPU ms, calling thread | CPU ms, process | peak MB | "
           "faces added |",
           "|---|---:|---:|---:|---:|---:|---:|",
           *[f"| {m['method']} | {fmt(m['median_ms']) if m.get('ok') else m.get('error')} | "
             f"{fmt(m.get('min_ms', 0))} | {fmt(runs[m['method']]['cpu_ms_calling_thread'])} | "
             f"{fmt(runs[m['method']]['cpu_ms_process'])} | {m.get('peak_rss_mb', 0):.0f} | "
             f"{format(m['result'], ',') if m.get('ok') else '–'} |"
             for m in (plain, checked)],
           "",
           "Stages of the untimed runs (wall ms, without / with the check): planning "
           f"{fmt(r['unchecked']['stage_ms']['plan'])} / {fmt(r['checked']['stage_ms']['plan'])}, "
           f"the check – / {fmt(r['checked']['stage_ms']['check'])}, writing "
           f"{fmt(r['unchecked']['stage_ms']['write'])} / "
           f"{fmt(r['checked']['stage_ms']['write'])}. Outcome: {o['faces_added']:,} faces, "
           f"border edges {o['border_edges_before']:,} → {o['border_edges_after']:,}, "
           f"{o['new_intersecting_pairs']} intersecting pairs.",
           "",
           f"**Acceptance target** (issue 8): stitching two paths of {paths // 1000}k vertices "
           f"each in under {target} ms: {fmt(plain['median_ms'])} ms wall without the check "
           f"({fmt(r['unchecked']['cpu_ms_calling_thread'])} ms CPU on the calling thread), "
           f"{'met' if met else 'not met'} on this run; with the check "
           f"{fmt(checked['median_ms'])} ms.",
           "",
           "**Close Gaps Between Borders** (`closeGaps` with the filter's defaults: orienting, "
           "merging at 0 tolerance, stitching within 1 % of the diagonal and, within one part, "
           "slits no wider than 1.5 times their border edges, each stitch checked, the result "
           "verified) against CGAL 5.5's `PMP::stitch_borders`, on the files of "
           "`../shared/data/stitching` as stored (an STL as its facet soup, three vertices per "
           "facet, for both; CGAL's `Surface_mesh` made from the same soup without merging its "
           "points). Both timed on a copy made in the timed run; *unverified* is ours without "
           "the exact count of the intersecting pairs left (the filter's verification; "
           "`stitch_borders` checks nothing); *border edges* are what each leaves.",
           "",
           "| file | faces | ours ms | ours ms, unverified | CGAL ms | CGAL / ours | "
           "border edges before | ours | CGAL |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    tmp = tempfile.mkdtemp(prefix="meshmend-bench-")
    for name in smallest(STITCHING_FILES, 2):
        path = data_file(f"stitching/{name}", tmp)
        print(name, file=sys.stderr)
        f = json.loads(subprocess.run([runner, "--repeat", str(repeat), str(path)],
                                      capture_output=True, text=True, check=True).stdout)
        by = {m["method"]: m for m in f["methods"]}
        ours, cgal = by["meshmend_close_gaps"], by["cgal_stitch_borders"]
        bare = by["meshmend_close_gaps_unverified"]
        ratio = (f"{cgal['median_ms'] / ours['median_ms']:.2f}×"
                 if ours.get("ok") and cgal.get("ok") and ours["median_ms"] > 0 else "–")
        out.append(f"| {name} | {f['faces']:,} | "
                   f"{fmt(ours['median_ms']) if ours.get('ok') else ours.get('error')} | "
                   f"{fmt(bare['median_ms']) if bare.get('ok') else bare.get('error')} | "
                   f"{fmt(cgal['median_ms']) if cgal.get('ok') else cgal.get('error')} | {ratio} | "
                   f"{f['outcome']['border_edges_before']:,} | "
                   f"{format(ours['result'], ',') if ours.get('ok') else '–'} | "
                   f"{format(cgal['result'], ',') if cgal.get('ok') else '–'} |")
    shutil.rmtree(tmp)
    out += ["",
            "What is left open: on `cgaltest_deg_border.off` the outer sides of the two fans "
            "(the zero-area face on CGAL's border collapses, so its three edges merge too); on "
            "`quads_to_stitch.off` the outline of the joined sheet (two strips of four quads, "
            "1 × 1 each, merged along their common side into one 1 × 2 sheet: 4 + 4 + 2 + 2 "
            "edges, which no closing of gaps can remove, so 12 is the least possible); on "
            "`cgaltest_pinched.off` the grid's outline (32 edges, likewise the least): its three "
            "slits one grid cell wide (0.1, 8.6 % of the diagonal, beyond the default `max_gap` "
            "of 1 %) are as narrow as their border edges, so the local bound closes them (the "
            "rest of the L-shaped one, if a first stitch leaves it, in a second round; "
            "`tests/integration/test_stitch.py`). "
            "`conrod.stl`'s facets are oriented against their neighbours: `stitch_borders` "
            "merges none of those edges, ours flips 2,170 facets first and closes the part; "
            "where two of its solids touch along an edge their vertices stay apart."]
    return "\n".join(out)


def write_section(name, title, body):
    text = DOC.read_text() if DOC.exists() else (
        "# Benchmarks\n\nSide-by-side measurements of MeshMend against its peers, written by "
        "`benchmarks/run.py`. Ratios matter more than absolute times: the machines are noisy.\n")
    begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
    section = f"{begin}\n## {title}\n\n{body}\n{end}"
    if begin in text:
        text = re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda _: section, text, flags=re.S)
    else:
        text = text.rstrip() + "\n\n" + section + "\n"
    DOC.write_text(text)


BENCHMARKS = {"intersections": ("Intersection detection", intersections),
              "split": ("Intersect and split", split),
              "selfintersect": ("Self-intersection removal", selfintersect),
              "holes": ("Hole filling", holes),
              "clearance": ("Minimum clearance", clearance),
              "stitch": ("Stitching and gap closing", stitch)}
# The runners each benchmark needs (the intersections also time the MeshLab filter).
TARGETS = {"intersections": RUNNERS, "split": ["bench_split"],
           "selfintersect": ["bench_selfintersect"], "holes": ["bench_holes"],
           "clearance": ["bench_clearance"], "stitch": ["bench_stitch"]}


def main():
    global DOC, SMOKE
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("benchmark", choices=[*BENCHMARKS, "all"])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--smoke", action="store_true",
                        help="one run of each on its smallest inputs, tables to build/benchmarks-smoke.md")
    parser.add_argument("--threads", type=int, default=0,
                        help="threads MeshMend's runners use (MESHMEND_THREADS; 0: every CPU); "
                             "the hole-filling comparison runs ours on 1 thread whatever this "
                             "says, and on every CPU beside it")
    args = parser.parse_args()
    if args.threads > 0:
        os.environ["MESHMEND_THREADS"] = str(args.threads)
    if not DATA.is_dir():
        # Every benchmark reads ../shared/data: without it none can run. In
        # CI that is a failure; elsewhere a skip that says why.
        if os.environ.get("CI") == "true":
            sys.exit(f"missing in CI: {DATA} (the benchmarks' meshes)")
        print(f"missing: {DATA} (the benchmarks' meshes live in ../shared beside the project)")
        sys.exit(SKIPPED)
    names = list(BENCHMARKS) if args.benchmark == "all" else [args.benchmark]
    if args.smoke:
        SMOKE, args.repeat = True, 1
        DOC = BUILD / "benchmarks-smoke.md"
        DOC.unlink(missing_ok=True)
    build_runners(sorted({t for name in names for t in TARGETS[name]}))
    for name in names:
        title, run = BENCHMARKS[name]
        started = time.time()
        write_section(name, title, run(args.repeat))
        print(f"{name}: {time.time() - started:.0f} s", file=sys.stderr)
    if SMOKE and "differ!" in DOC.read_text():
        sys.exit(f"a method disagrees with its peer on a count: see {DOC}")
    print(f"updated {DOC}")


if __name__ == "__main__":
    main()
