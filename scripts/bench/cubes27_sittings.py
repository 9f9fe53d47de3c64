"""The issue-16 targets of several bench_cubes27.py runs side by side: per
run (a JSON written by bench_cubes27.py) its OpenMP wait policy, the four
target figures and the load it ran at; then per label the median over the
runs and the range.  Labels come from the file names: a run named
cubes27_<sitting>_<label>_<date>.json (e.g. ..._a_new_passive_...) counts
for <label>.

    /usr/bin/python3.11 scripts/bench/cubes27_sittings.py bench/logs/cubes27_s12_*_2026-11-24.json
"""
import json
import os
import re
import statistics
import sys

TARGETS = [("ours_whole_step_ns_per_tet_2_threads", "whole step, ns/tet (2 thr; target <= 15)"),
           ("ours_rebuild_over_ordinary_step_2_threads", "rebuild / ordinary (target <= 1.3)"),
           ("contact_A_over_ours_2_threads", "contacts vs case A (target >= 10)"),
           ("ours_speedup_1_to_2_threads", "1 -> 2 threads (target >= 1.8)")]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    byLabel = {}
    for path in sys.argv[1:]:
        d = json.load(open(path))
        m = re.match(r"cubes27_[^_]+_(?P<sit>[^_]+)_(?P<label>.+)_\d{4}-\d\d-\d\d\.json$", os.path.basename(path))
        label = m.group("label") if m else os.path.basename(path)
        loads = [r["load1"] for t in d["threads"].values() for r in t["ours"]["runs"]]
        byLabel.setdefault(label, []).append({k: d["targets"][k]["measured"] for k, _ in TARGETS})
        print("%-40s %-8s %s  load %.2f-%.2f" % (os.path.basename(path), d.get("OMP_WAIT_POLICY") or "default",
                                                "  ".join("%.2f" % d["targets"][k]["measured"] for k, _ in TARGETS),
                                                min(loads), max(loads)))
    print()
    print("| runs | " + " | ".join(name for _, name in TARGETS) + " |")
    print("| --- |" + " --- |" * len(TARGETS))
    for label, rows in byLabel.items():
        cells = []
        for k, _ in TARGETS:
            v = [r[k] for r in rows]
            cells.append("%.2f (%.2f–%.2f)" % (statistics.median(v), min(v), max(v)))
        print("| %s (%d) | %s |" % (label, len(rows), " | ".join(cells)))


if __name__ == "__main__":
    main()
