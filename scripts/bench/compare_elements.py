"""Old build against new build on the element benchmark, interleaved in one
sitting: each round runs both bench_elements binaries once (--repeats 1),
old first in even rounds and new first in odd ones; per case (mesh, law,
mode, threads) the medians of each build and the median of the paired
per-round ratios new / old, over the rounds in which neither run was busy
(over all rounds, said so, when there is no such pair).

    /usr/bin/python3.11 scripts/bench/compare_elements.py OLD/bench_elements NEW/bench_elements \\
        [--rounds 5] [--args "--cubes 3 --steps 200"] [--out compare.json]

Both binaries must be built from this commit's scripts/bench/bench_elements.cpp
(an older one did not Hilbert-order its meshes, and prints another JSON):
build the old commit with this file, BenchStats.hpp and MachineLoad.hpp copied
into its scripts/bench/."""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys

FIGURES = ["whole_step", "element_integrate", "element", "whole_step_on_cpu"]
RUN_KEYS = {"whole_step": "step", "element": "element", "whole_step_on_cpu": "step_on_cpu"}


def runOnce(binary, args):
    env = dict(os.environ, OMP_WAIT_POLICY="passive")
    p = subprocess.run([binary, "--repeats", "1"] + args, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit("compare_elements: %s failed:\n%s" % (binary, p.stderr[-2000:]))
    d = json.loads(p.stdout)
    if "meshes" not in d:
        sys.exit("compare_elements: %s prints the former JSON (no 'meshes'): build it with this commit's "
                 "scripts/bench/bench_elements.cpp, BenchStats.hpp and MachineLoad.hpp" % binary)
    out = {}
    for mesh in d["meshes"]:
        for c in mesh["cases"]:
            r = c["runs"][0]
            fig = {k: r.get(v) for k, v in RUN_KEYS.items()}
            fig["element_integrate"] = r["element"] + r["integrate"]
            out[(mesh["tets"], c["law"], c["mode"], c["threads"])] = dict(fig, busy=r["busy"])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--args", default="", help="more bench_elements options, e.g. \"--cubes 3 --steps 200\"")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    if a.rounds < 1:
        ap.error("--rounds must be at least 1")
    extra = shlex.split(a.args)
    rounds = []
    for r in range(a.rounds):
        order = [("old", a.old), ("new", a.new)] if r % 2 == 0 else [("new", a.new), ("old", a.old)]
        res = {tag: runOnce(binary, extra) for tag, binary in order}
        rounds.append(res)
        print("round %d done (%s first)" % (r, order[0][0]), file=sys.stderr, flush=True)
    table = []
    for case in rounds[0]["old"]:
        pairs = [(x["old"][case], x["new"][case]) for x in rounds if case in x["new"]]
        quiet = [(o, n) for o, n in pairs if not o["busy"] and not n["busy"]]
        use, source = (quiet, "quiet pairs") if quiet else (pairs, "all pairs (every round busy)")
        row = {"tets": case[0], "law": case[1], "mode": case[2], "threads": case[3], "pairs": len(use),
               "from": source}
        for f in FIGURES:
            o = [p[0][f] for p in use if p[0][f] is not None]
            n = [p[1][f] for p in use if p[1][f] is not None]
            ratios = [p[1][f] / p[0][f] for p in use if p[0][f] and p[1][f] is not None]
            row[f] = {"old_median": statistics.median(o) if o else None, "old_min": min(o) if o else None,
                      "new_median": statistics.median(n) if n else None, "new_min": min(n) if n else None,
                      "ratio_new_over_old_median": statistics.median(ratios) if ratios else None}
        table.append(row)
    print("| tets | law | mode | threads | element+integration old → new (median) | ratio | "
          "whole step on CPU old → new | ratio | pairs |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for row in table:
        ei, cpu = row["element_integrate"], row["whole_step_on_cpu"]
        print("| %d | %s | %s | %d | %.2f → %.2f | %.3f | %s | %s | %d %s |" % (
            row["tets"], row["law"], row["mode"], row["threads"], ei["old_median"], ei["new_median"],
            ei["ratio_new_over_old_median"],
            "%.2f → %.2f" % (cpu["old_median"], cpu["new_median"]) if cpu["old_median"] else "—",
            "%.3f" % cpu["ratio_new_over_old_median"] if cpu["ratio_new_over_old_median"] else "—",
            row["pairs"], row["from"]))
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"old": a.old, "new": a.new, "rounds": a.rounds, "args": extra, "cases": table,
                       "raw": [{t: {"%s %s %s %s" % k: v for k, v in x[t].items()} for t in x} for x in rounds]},
                      f, indent=1)


if __name__ == "__main__":
    main()
