"""Old build against new build on element_parts (the element kernel taken
apart: gather, arithmetic, scatter; one thread, thread CPU time), interleaved
in one sitting: each round runs both binaries (old first in even rounds, new
first in odd ones) with --rounds 5 --passes 10, and per law, mode and part
prints both builds' medians (min) over the rounds' medians and the median
[range] of the paired per-round ratios new / old.  The 1-minute load before
each run is kept in the JSON.

    /usr/bin/python3.11 scripts/bench/element_parts_compare.py OLD/element_parts build/element_parts ROUNDS OUT.json
"""
import json
import os
import statistics
import subprocess
import sys

if len(sys.argv) != 5:
    sys.exit(__doc__)
old, new, n, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
env = dict(os.environ, OMP_NUM_THREADS="1")
runs = []
for r in range(n):
    order = [("old", old), ("new", new)] if r % 2 == 0 else [("new", new), ("old", old)]
    for name, b in order:
        load = open("/proc/loadavg").read().split()[0]
        o = subprocess.run([b, "--rounds", "5", "--passes", "10"], capture_output=True, text=True, env=env, check=True).stdout
        d = json.loads(o)
        runs.append({"build": name, "round": r, "load1": float(load), "result": d})
json.dump(runs, open(out, "w"), indent=1)
def get(run, law, mode, mesh, var):
    for c in run["result"]["cases"]:
        if c["law"] == law and c["mode"] == mode:
            return c[mesh][var]["cpu"]["median"]
cases = [(c["law"], c["mode"]) for c in runs[0]["result"]["cases"]]
for law, mode in cases:
    for var in ["gather+arithmetic+scatter", "arithmetic", "gather+arithmetic", "arithmetic+scatter"]:
        o = [get(x, law, mode, "mesh", var) for x in runs if x["build"] == "old"]
        nw = [get(x, law, mode, "mesh", var) for x in runs if x["build"] == "new"]
        ratios = [b / a for a, b in zip(o, nw)]
        print(f"{law} {mode:8s} {var:26s} old {statistics.median(o):6.2f} ({min(o):6.2f})  new {statistics.median(nw):6.2f} ({min(nw):6.2f})  new/old median {statistics.median(ratios):.3f} [{min(ratios):.3f}-{max(ratios):.3f}]")
print("load1", [x["load1"] for x in runs])
