"""A shogi scene at REAL size run to its end, its wall time kept as a
whole-run log for the time-to-solution table (doc/performance.md):
bench/logs/time_to_solution_full_<scene>_real_size_mu<friction>.json,
which scripts/bench/bench_time_to_solution.py copies into "full_runs".

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 \
        scripts/shogi/time_to_solution_full.py two_rooks|king_and_pawns [--threads 2] [--lever cholesky] \
        [--max-s 0.3] [--logs bench/logs]

The scene as bench_time_to_solution.py builds it (Table 1's material, the
particle radius scaled with the pieces, bare core world, the floor as stiff
as the pieces, gravity, implicit viscosity at 0.8 of its stable step), from
its set-up (the first piece tipped) until every piece has fallen (centre of
mass below 70 % of its standing height, as domino.py counts a fall) or
--max-s simulated seconds.  Wall and CPU time of the whole run, each
piece's fall time, the load average sampled every 10,000 steps.
"""
import argparse
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "bench"))

from qdem import _core  # noqa: E402
import bench_time_to_solution as tts  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", choices=["two_rooks", "king_and_pawns"])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--lever", default=tts.NEW, choices=list(tts.LEVERS))
    ap.add_argument("--max-s", type=float, default=0.3, help="stop here if not every piece has fallen [s]")
    ap.add_argument("--logs", default="bench/logs")
    a = ap.parse_args()
    _core.setThreads(a.threads)
    w, pieces, H = tts.build(tts.SCENES[a.scene][0], 1.0)
    for k, v in tts.LEVERS[a.lever].items():
        setattr(w.core, k, v)
    dt = tts.DT_FACTOR * w.stableDt()["combinedImplicit"]
    z0 = [p.centroid[2] for p in pieces]
    fallen = [None] * len(pieces)
    loads, steps, its, chunk = [os.getloadavg()[0]], 0, 0, 1000
    cpu0, t0 = time.process_time(), time.perf_counter()
    while None in fallen and w.core.time < a.max_s:
        for _ in range(chunk):
            w.core.step(dt, 1)
            its += w.core.counts.get("viscousIterations", 0)
        steps += chunk
        for i, p in enumerate(pieces):
            if fallen[i] is None and p.centroid[2] < 0.7 * z0[i]:
                fallen[i] = w.core.time
                print("full run %s: piece %d fallen at %.5g s (%d steps, %.0f s wall)" % (
                    a.scene, i + 1, w.core.time, steps, time.perf_counter() - t0), flush=True)
        if steps % 10000 == 0:
            loads.append(os.getloadavg()[0])
            if steps % 100000 == 0:
                print("full run %s: t = %.5g s, %d steps, %.0f s wall, load %.2f" % (
                    a.scene, w.core.time, steps, time.perf_counter() - t0, loads[-1]), flush=True)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    name = "%s_real_size_mu%g" % (a.scene, tts.FRICTION)
    out = {"benchmark": "time_to_solution_full_run", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "name": name, "scene": tts.SCENES[a.scene][0], "scale": 1.0, "frictionPiece": tts.FRICTION,
           "lever": a.lever, "settings": tts.LEVERS[a.lever], "threads": a.threads,
           "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "(libgomp default)"),
           "tets": w.core.nTets, "pieces": w.core.nPieces, "dt": dt, "steps": steps,
           "simulated_s": w.core.time, "ended": "every piece fallen" if None not in fallen else
           "stopped at --max-s %g s with pieces standing" % a.max_s,
           "fallen_s": fallen, "wall_s": wall, "cpu_s": cpu, "cg_iterations_per_step": its / max(steps, 1),
           "load1": {"min": min(loads), "median": statistics.median(loads), "max": max(loads)}}
    path = os.path.join(a.logs, "time_to_solution_full_%s.json" % name)
    os.makedirs(a.logs, exist_ok=True)
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    print("full run %s: %s at %.5g s simulated, %d steps, %.0f s wall (CPU %.0f s), %.2f CG its/step -> %s" % (
        a.scene, out["ended"], w.core.time, steps, wall, cpu, out["cg_iterations_per_step"], path))


if __name__ == "__main__":
    main()
