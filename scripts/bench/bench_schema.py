"""The keys each benchmark JSON must hold: what perf_tables.py and the docs
read from it (doc/performance.md, doc/spheres.md; the MPI logs printed on
doc/parallel.md and doc/parallel_scaling.md are checked by running each
table's generator on its kept JSON, tests/python/test_doc_generated_tables.py).  A key
path is dotted; "[]" means every element of a list (or every value of a
dict) must hold the rest.  `make bench` checks out/bench/ at its end (every
file named in SCHEMA must be there and complete); the tests check every
kept log under bench/logs/ whose "benchmark" field names one of them
(tests/python/test_bench_tools.py).

    /usr/bin/python3.11 scripts/bench/bench_schema.py out/bench --expect   # exit 1 naming what is wrong
    /usr/bin/python3.11 scripts/bench/bench_schema.py bench/logs           # the kept logs
"""
import json
import os
import sys

# file name (out/bench) -> required key paths
SCHEMA = {
    "roofline.json": ["isa", "date", "results.[].name", "results.[].threads", "results.[].unit",
                      "results.[].all", "results.[].on_cpu.all"],
    "kernel_ops.json": ["source", "kernel.[].per_tet", "kernel.[].flops_per_tet", "per_tet.[].flops",
                        "per_tet.[].bytes"],
    "omp_sync.json": ["benchmark", "rounds", "summary", "runs"],
    "elements_qdem.json": ["date", "meshes.[].tets", "meshes.[].nodes", "meshes.[].steps",
                           "meshes.[].cases.[].law", "meshes.[].cases.[].mode", "meshes.[].cases.[].threads",
                           "meshes.[].cases.[].all.element_integrate", "meshes.[].cases.[].all.whole_step"],
    "elements.json": ["qdem_ns_per_tet_step", "yade_fem_over_qdem"],
    "cubes27.json": ["tets", "scene", "date", "threads", "targets"],
    "shogi.json": ["date", "scenes.[].pieces", "scenes.[].tets", "scenes.[].steps", "scenes.[].all.ms_per_step",
                   "scenes.[].all.wall_s_per_simulated_s", "scales.runs"],
    "effects.json": ["threads", "steps", "rounds", "date", "statistic", "effects.[].all", "effects.[].qdem.all",
                     "effects.[].paired.on_over_off.qdem", "effects.[].paired.zero_over_off.qdem",
                     "effects.[].paired.zero_over_off.whole", "effects.[].paired.zero_over_off.cpu",
                     "effects.[].on_cpu.all"],
    "time_to_solution.json": (
        ["benchmark", "date", "threads", "old", "new", "levers"]
        + [("scenes", "%s_%s" % (n, x), k) for n in ("two_rooks", "king_and_pawns", "forty_front")
           for x in ("766x", "real_size") for k in ("scale", "pieces")]
        + ["scenes.[].%s.%s" % (k, v) for k in ("wall_s_per_simulated_s", "cpu_s_per_simulated_s",
                                               "cg_iterations_per_step") for v in ("old", "new")]
        + ["scenes.[].load1", "scenes.[].levers", "scenes.[].projected_full_run.wall_s"]
        + [("full_runs", n, "wall_s") for n in ("forty_real_size_mu0.1", "forty_real_size_mu0.5")]
        + ["full_runs.[].status"]),
    "spheres.json": ["benchmark", "date", "spheres", "near.coupling_ms_per_step", "near.yade_ms_per_step", "near.spheres_listed",
                     "far.coupling_ms_per_step", "far.yade_ms_per_step", "coupling_fraction_near",
                     "coupling_fraction_far", "per_listed_sphere_us", "fixed_cost_ms_per_step"],
}
# What `make bench` writes besides (not read by the docs' tables): they must exist.
ALSO_WRITTEN = ["element_parts.json", "yade_fem.json"]


def missing(d, path):
    """The first part of a key path that d lacks, or None.  A path is dotted
    ("a.b") or a tuple of keys (for keys holding a dot: ("a", "mu0.1"))."""
    if isinstance(path, (tuple, list)):
        head, rest = path[0], tuple(path[1:])
    else:
        head, _, rest = path.partition(".")
    if head == "[]":
        items = d.values() if isinstance(d, dict) else d if isinstance(d, list) else None
        if not items:
            return "[] (empty or not a list)"
        for x in items:
            m = missing(x, rest) if rest else None
            if m:
                return "[]." + m
        return None
    if not isinstance(d, dict) or head not in d:
        return head
    return missing(d[head], rest) if rest else None


def checkFile(path, keys, name=None):
    """Problems of one JSON file against its key paths and the RULES of
    `name` (its SCHEMA name; the file's own name by default); empty: fine."""
    try:
        with open(path) as f:
            d = json.load(f)
    except FileNotFoundError:
        return ["%s: missing (its benchmark failed or was not run)" % path]
    except (OSError, ValueError) as e:
        return ["%s: not readable JSON (%s)" % (path, e)]
    out = []
    for k in keys:
        m = missing(d, k)
        if m is not None:
            out.append("%s: lacks %s (at %s)" % (path, k if isinstance(k, str) else ".".join(k), m))
    for rule in RULES.get(name or os.path.basename(path), []):
        out += ["%s: %s" % (path, p) for p in rule(d)]
    return out


def fullRunsRule(d):
    """A whole run's wall time is measured (status "measured") or null with
    status "not run" and a projected_wall_s beside it: never a made-up figure."""
    out = []
    for name, r in (d.get("full_runs") or {}).items():
        if not isinstance(r, dict):
            out.append("full_runs.%s is not an object" % name)
        elif r.get("wall_s") is None:
            if r.get("status") != "not run" or "projected_wall_s" not in r:
                out.append("full_runs.%s: wall_s null needs status 'not run' and projected_wall_s" % name)
        elif r.get("status") != "measured":
            out.append("full_runs.%s: a wall_s needs status 'measured' (a kept run's log)" % name)
    return out


# Checks beyond the keys' presence, per file.
RULES = {"time_to_solution.json": [fullRunsRule]}


# The "benchmark" field of each file above (kept logs are recognised by it),
# and the keys a kept log need not hold (added to the file by a later script).
BENCHMARK = {"roofline.json": "roofline", "omp_sync.json": "omp_sync", "elements_qdem.json": "bench_elements",
             "cubes27.json": "bench_cubes27", "shogi.json": "bench_shogi", "effects.json": "bench_effects",
             "spheres.json": "bench_spheres", "time_to_solution.json": "bench_time_to_solution"}
LATER = {"shogi.json": ["scales.runs"]}
# Keys a benchmark has written only since a date (ISO, compared with the
# log's "date"): older kept logs are checked without them.
SINCE = {"effects.json": ("2026-11-28", ["statistic", "effects.[].qdem.all", "effects.[].paired.on_over_off.qdem",
                                         "effects.[].paired.zero_over_off.qdem",
                                         "effects.[].paired.zero_over_off.whole",
                                         "effects.[].paired.zero_over_off.cpu", "effects.[].on_cpu.all"])}


def keysFor(name, date):
    """The keys a kept log of `name` dated `date` must hold."""
    since, newer = SINCE.get(name, ("", []))
    old = str(date or "") < since
    return [k for k in SCHEMA[name] if k not in LATER.get(name, []) and not (old and k in newer)]


def checkOutput(folder):
    """Problems of `make bench`'s output folder: every file there, complete."""
    problems = []
    for name, keys in SCHEMA.items():
        problems += checkFile(os.path.join(folder, name), keys)
    for name in ALSO_WRITTEN:
        problems += checkFile(os.path.join(folder, name), [])
    return problems


def checkLogs(folder):
    """Problems of the kept logs: each JSON readable, and each one whose
    "benchmark" field names a benchmark above holding that file's keys."""
    problems = []
    byBenchmark = {b: n for n, b in BENCHMARK.items()}
    for entry in sorted(os.listdir(folder)):
        if not entry.endswith(".json"):
            continue
        p = os.path.join(folder, entry)
        try:
            with open(p) as f:
                d = json.load(f)
        except (OSError, ValueError) as e:
            problems.append("%s: not readable JSON (%s)" % (p, e))
            continue
        name = byBenchmark.get(d.get("benchmark")) if isinstance(d, dict) else None
        if name:
            problems += checkFile(p, keysFor(name, d.get("date")), name)
    return problems


if __name__ == "__main__":
    folder = sys.argv[1] if len(sys.argv) > 1 else "out/bench"
    problems = checkOutput(folder) if "--expect" in sys.argv else checkLogs(folder)
    for p in problems:
        print("bench: " + p)
    if problems:
        sys.exit(1)
    print("bench: every benchmark JSON in %s holds the keys the docs read" % folder)
