"""Cost of the surface-spin pass (the spins piece-piece springs turn by,
doc/formulation.md "Twist"): its time per step over the surface nodes it
computed, in the 27-cube pile (bench_cubes27.scene, thrown at 1 m/s), at
one thread.  Several rounds of `steps` steps each; prints the minimum and
median ns per node per step (wall; and on the CPU: wall times this
process's CPU time over the round's wall time, for a shared machine), its
share of the contact kernels' time, and the load average.

    /usr/bin/python3.11 scripts/bench/bench_surface_spin.py [--steps 100] [--rounds 5] [--json OUT.json]

With --json the rounds and their summary are written as JSON (kept in
bench/logs/ for doc/performance.md, "Surface spin of piece-piece contacts").
"""
import argparse
import json
import os
import resource
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from qdem import _core  # noqa: E402

import bench_cubes27  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--json", help="write the rounds and their summary to this file")
    a = ap.parse_args()
    _core.setThreads(1)
    w = bench_cubes27.scene(throw=1.0)
    w.core.step(bench_cubes27.DT, 5)
    perNode, onCpu, share = [], [], []

    def cpu():
        r = resource.getrusage(resource.RUSAGE_SELF)
        return r.ru_utime + r.ru_stime
    load0 = os.getloadavg()[0]
    for _ in range(a.rounds):
        sec = nodes = pp = 0.0
        wall0, cpu0 = time.perf_counter(), cpu()
        for _ in range(a.steps):
            w.core.step(bench_cubes27.DT, 1)
            t = w.core.timings
            sec += t["surfaceSpin"]
            pp += t["pointPolygon"] + t["edgeEdge"]
            nodes += w.core.contactCounts["surfaceSpinNodes"]
        perNode.append(1e9 * sec / nodes)
        onCpu.append(perNode[-1] * (cpu() - cpu0) / (time.perf_counter() - wall0))
        share.append(sec / pp)
    print("surface spin: %d nodes a step; ns/node/step wall min %.1f median %.1f, on the CPU min %.1f median %.1f; "
          "%.1f %% of point-polygon + edge-edge (median); load average %.1f -> %.1f" % (
              nodes / a.steps, min(perNode), statistics.median(perNode), min(onCpu), statistics.median(onCpu),
              100 * statistics.median(share), load0, os.getloadavg()[0]))
    if a.json:
        summary = {"min": min(perNode), "median": statistics.median(perNode)}
        with open(a.json, "w") as f:
            json.dump({"benchmark": "bench_surface_spin", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                       "scene": "27-cube pile (bench_cubes27.scene), thrown at 1 m/s", "threads": 1,
                       "steps": a.steps, "rounds": a.rounds, "surface_nodes": nodes / a.steps,
                       "load1": {"before": load0, "after": os.getloadavg()[0]},
                       "ns_per_node_step": dict(summary, rounds=perNode),
                       "ns_per_node_step_on_cpu": {"min": min(onCpu), "median": statistics.median(onCpu),
                                                   "rounds": onCpu},
                       "share_of_point_polygon_edge_edge": {"median": statistics.median(share), "rounds": share}},
                      f, indent=1)


if __name__ == "__main__":
    main()
