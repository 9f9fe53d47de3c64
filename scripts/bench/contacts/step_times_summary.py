"""The figures of contact_step_times.py's JSON files, busy runs included: on a
shared machine a whole sitting can run above the --busy load, and then the
script's own table (busy runs left out) is empty.  Per thread count and
build: median and min over the rounds of each process's median (ordinary
step, point-polygon in ordinary steps, step with a rebuild, the amortised
ns/tet), the 1-minute load range, and per round the new/old ratios of the
ordinary step and of point-polygon (the builds run back to back in a round,
so a burst of load hits both alike).

    /usr/bin/python3.11 scripts/bench/contacts/step_times_summary.py \
        bench/logs/contacts_step_times_pp2_2026-11-24.json [more.json ...]
"""
import json
import statistics as st
import sys

KEYS = [("ordinary_ms", "ordinary step, ms"), ("pointPolygon", "point-polygon (ordinary steps), ms"),
        ("rebuild_ms", "step with a rebuild, ms"), ("step_ns_per_tet", "whole step amortised, ns/tet")]


def summary(path):
    d = json.load(open(path))
    runs = d["runs"]
    builds = []
    for r in runs:
        if r["build"] not in builds:
            builds.append(r["build"])
    out = dict(file=path, builds=builds, rows={})
    print(path)
    for th in sorted({r["threads"] for r in runs}):
        loads = [r["load_before"][0] for r in runs if r["threads"] == th]
        busy = sum(r["busy"] for r in runs if r["threads"] == th)
        print("  %d thread(s): 1-minute load %.2f-%.2f, %d of %d processes above the --busy load"
              % (th, min(loads), max(loads), busy, len(loads)))
        row = dict(load=[min(loads), max(loads)], busy=busy, processes=len(loads))
        for k, name in KEYS:
            cells = []
            for b in builds:
                xs = [r["summary"][k] for r in runs if r["threads"] == th and r["build"] == b and r["summary"][k]]
                row.setdefault(k, {})[b] = dict(median=st.median(xs), min=min(xs), n=len(xs))
                cells.append("%.2f (%.2f)" % (st.median(xs), min(xs)))
            print("    %-36s %s" % (name, "  ->  ".join(cells)))
        for k in ["ordinary_ms", "pointPolygon"]:
            ratios = []
            for rnd in sorted({r["round"] for r in runs}):
                o = [r for r in runs if r["round"] == rnd and r["threads"] == th and r["build"] == builds[0]]
                n = [r for r in runs if r["round"] == rnd and r["threads"] == th and r["build"] == builds[-1]]
                if o and n:
                    ratios.append(n[0]["summary"][k] / o[0]["summary"][k])
            row[k + "_ratios"] = ratios
            print("    new/old per round, %-14s median %.3f  [%s]"
                  % (k, st.median(ratios), " ".join("%.2f" % x for x in ratios)))
        out["rows"][th] = row
    return out


if __name__ == "__main__":
    for p in sys.argv[1:]:
        summary(p)
