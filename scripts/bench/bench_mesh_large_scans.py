"""qdem.meshSurface's time on large generated scans (an isosurface of a
bunny-like figurine with thin ears, a ball with a plate standing out of it,
a bumpy ball; 40,000 to 110,000 triangles), with the load average, the
worst element against the median one and the volume kept.

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/bench_mesh_large_scans.py [label] [out.json]

Appends one run (label: e.g. the commit) to bench/logs/mesh_large_scans.json."""
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "python"))

import qdem  # noqa: E402
import testsurfaces as ts  # noqa: E402


def diagonal(s):
    v = np.asarray(s[0])
    return float(np.linalg.norm(v.max(0) - v.min(0)))


CASES = [
    ("bunny-like scan, ears 0.06 thick, diagonal/14", lambda: ts.bunny(ears=0.06), None),
    ("bunny-like scan, ears 0.14 thick, diagonal/14", lambda: ts.bunny(ears=0.14), None),
    ("bunny-like scan at spacing 1/100 (ears 0.06), diagonal/14", lambda: ts.bunny(ears=0.06, spacing=0.01), None),
    ("ball + plate 0.04 thick, cellSize 0.1", lambda: ts.bodyWithPlate(0.04), 0.1),
    ("bumpy ball (scan), diagonal/14", lambda: ts.bumpyBall(), None),
]


def main(label, out):
    rows = []
    for name, make, h in CASES:
        s = make()
        h = h or diagonal(s) / 14
        load = os.getloadavg()[0]
        t0, c0 = time.perf_counter(), time.process_time()
        m = qdem.meshSurface(s, h)
        dt, cpu = time.perf_counter() - t0, time.process_time() - c0
        rows.append({"case": name, "cellSize": round(h, 5), "inputTriangles": int(len(s[1])), "tets": int(m.nTets),
                     "seconds": round(dt, 2), "cpuSeconds": round(cpu, 2), "stepFactor": round(ts.stepFactor(m), 2),
                     "volumeKept": round(m.volumeKept, 5), "passes": m.meshReport["passes"],
                     "load1Before": round(load, 2), "load1After": round(os.getloadavg()[0], 2)})
        print(json.dumps(rows[-1]), flush=True)
    runs = []
    if os.path.exists(out):
        with open(out) as f:
            runs = json.load(f)["runs"]
    try:
        commit = subprocess.check_output(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, text=True).strip()
    except Exception:
        commit = None
    runs.append({"label": label, "commit": commit, "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                 "threads": 1, "cores": os.cpu_count(), "rows": rows})
    with open(out, "w") as f:
        json.dump({"what": "qdem.meshSurface wall time on large generated scans, one thread, on a shared machine "
                           "(seconds: wall time, cpuSeconds: the process's CPU time, which the load does not inflate; load1: the 1-minute load average before and after each case); stepFactor = median / "
                           "smallest of the tets' smallest heights; volumeKept = mesh volume / enclosed volume",
                   "runs": runs}, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "run",
         sys.argv[2] if len(sys.argv) > 2 else os.path.join(HERE, "..", "..", "bench", "logs", "mesh_large_scans.json"))
