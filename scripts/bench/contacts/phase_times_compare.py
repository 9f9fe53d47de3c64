"""Two builds' per-phase times on the moving 27-cube stack, interleaved: for
each round, each thread count and each build (in that order), one fresh
process of phase_times.py (the median over --steps ordinary and rebuild
steps of each phase's own timing).  Prints per build and thread count the
min and median over the rounds of each phase, and the median of the paired
new/old ratios (round by round); writes the runs, with the load average read
before each, as JSON.

    /usr/bin/python3.11 scripts/bench/contacts/phase_times_compare.py --old DIR --new DIR \\
        [--threads 1 2] [--rounds 6] [--steps 100] [--policy passive|default] [--out FILE.json]

DIR: a directory holding the `qdem` package (a build's `python` directory).
The machine is shared: runs whose 1-minute load average exceeded the thread
count + 0.5 before they started are flagged "busy" (kept in the JSON, left
out of the figures)."""
import argparse
import datetime
import json
import os
import statistics as st
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def run(build, threads, steps, policy):
    env = dict(os.environ, PYTHONPATH=os.path.abspath(build), OMP_NUM_THREADS=str(threads))
    env.pop("OMP_WAIT_POLICY", None)
    if policy != "default":
        env["OMP_WAIT_POLICY"] = policy
    load = os.getloadavg()[0]
    out = subprocess.run([sys.executable, os.path.join(HERE, "phase_times.py"), str(threads), "--steps", str(steps)],
                         env=env, check=True, capture_output=True, text=True).stdout.split()
    phases = {out[i]: float(out[i + 1]) for i in range(1, len(out) - 1, 2)}
    return {"load1": load, "busy": load > threads + 0.5, "ms": phases}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--old", required=True)
    ap.add_argument("--new", required=True)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--policy", default="passive", help="OMP_WAIT_POLICY for the runs ('default': unset)")
    ap.add_argument("--label", default="")
    ap.add_argument("--out")
    a = ap.parse_args()
    runs = {b: {t: [] for t in a.threads} for b in ("old", "new")}
    for r in range(a.rounds):
        for t in a.threads:
            for b in ("old", "new"):
                runs[b][t].append(run(getattr(a, b), t, a.steps, a.policy))
        print("round %d/%d done (load %.2f)" % (r + 1, a.rounds, os.getloadavg()[0]), file=sys.stderr, flush=True)
    summary = {}
    for t in a.threads:
        quiet = [i for i in range(a.rounds) if not runs["old"][t][i]["busy"] and not runs["new"][t][i]["busy"]]
        phases = list(runs["old"][t][0]["ms"])
        rows = {}
        for ph in phases + ["sum"]:
            def val(b, i):
                m = runs[b][t][i]["ms"]
                return sum(m.values()) if ph == "sum" else m.get(ph, 0.0)
            row = {}
            for b in ("old", "new"):
                v = [val(b, i) for i in quiet]
                row[b] = {"min": min(v), "median": st.median(v)} if v else None
            ratios = [val("new", i) / val("old", i) for i in quiet if val("old", i) > 0]
            row["ratio_median"] = st.median(ratios) if ratios else None
            row["ratio_range"] = [min(ratios), max(ratios)] if ratios else None
            rows[ph] = row
        summary[t] = {"quiet_rounds": len(quiet), "phases": rows}
        print("%d thread(s), %d/%d quiet rounds; ms: old median (min) -> new median (min), paired new/old median [range]"
              % (t, len(quiet), a.rounds))
        for ph, row in rows.items():
            if row["old"] is None:
                continue
            print("  %-12s %7.3f (%.3f) -> %7.3f (%.3f)   %.3f [%.3f-%.3f]" % (
                ph, row["old"]["median"], row["old"]["min"], row["new"]["median"], row["new"]["min"],
                row["ratio_median"], *row["ratio_range"]))
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"benchmark": "phase_times_compare", "label": a.label,
                       "date": datetime.datetime.utcnow().isoformat(timespec="seconds") + "Z",
                       "old": a.old, "new": a.new, "steps": a.steps, "rounds": a.rounds,
                       "OMP_WAIT_POLICY": a.policy, "busy_rule": "1-minute load > threads + 0.5 before the run",
                       "runs": runs, "summary": summary}, f, indent=1)


if __name__ == "__main__":
    main()
