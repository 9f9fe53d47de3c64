"""The implicit viscous solve's preconditioners compared on the two-rook scene
at REAL size (Table 1's material, no 766x scaling, the particle radius scaled
alike, implicit viscosity at 0.8 of its stable step): CG iterations per step
and ms per step with viscousPreconditioner 'jacobi' and 'cholesky'.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 \
        scripts/shogi/precond_bench.py [--steps 300] [--rounds 3] [--threads 1] [--warmup 200] \
        [--log bench/logs/precond_two_rooks.json]

The scene (time_to_solution_baseline.py's world: bare core world, the floor as
stiff as the pieces, gravity) is stepped `--warmup` steps from its set-up (the
first rook tipped towards the second, both settling on the floor), its state
kept, then `--steps` steps are timed `--rounds` times per preconditioner,
interleaved (jacobi, cholesky, jacobi, ...), the state reloaded before each
round so that every round covers the same steps.  Wall and CPU time, the
viscousSolve phase, the load average before and after and other processes'
CPU during each round (benchutil.LoadProbe).  Min and median per preconditioner.
"""
import argparse
import json
import os
import statistics
import sys
import time

import qdem
from qdem import _core
from qdem.scenes import shogi

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from benchutil import BUSY_RULE, floorAndGravity, timedWindow  # noqa: E402

G = 9.80665
TABLE1_SCALE = 766  # scales.table1Scale() (bench/logs/time_to_solution_baseline.json)
NAMES = {0: "jacobi", 1: "cholesky"}


def build():
    w = qdem.World()
    mat = qdem.QdemMat(frictionPiece=0.1, radius=qdem.QdemMat().radius / TABLE1_SCALE)
    shogi.scene("two_rooks", mat, 1.0, world=w)
    floorAndGravity(w, G, young=max(1e7, mat.young))  # the floor as domino.py's
    w.core.viscousIntegration = 1
    w.core.viscousWarmStart = True
    return w


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--log", default="bench/logs/precond_two_rooks.json")
    a = ap.parse_args()
    _core.setThreads(a.threads)
    w = build()
    dt = 0.8 * w.stableDt()["combinedImplicit"]
    w.core.viscousPreconditioner = 1
    w.core.step(dt, a.warmup)
    state = w.core.saveState()
    runs = {0: [], 1: []}
    for r in range(a.rounds):
        for pre in (0, 1):
            w.core.loadState(state)
            w.core.viscousPreconditioner = pre
            w.core.step(dt, 3)  # lists, layout and (cholesky) factors built anew after loading
            rec, its, phases = timedWindow(w, dt, a.steps)
            wall, cpu, solve = rec["wall_s"], rec["cpu_s"], phases.get("viscousSolve", 0.0)
            rec.update(ms_per_step=1e3 * wall / a.steps, cpu_ms_per_step=1e3 * cpu / a.steps,
                       solve_ms_per_step=1e3 * solve / a.steps, cg_iterations_per_step=its / a.steps)
            runs[pre].append(rec)
            print("round %d %-8s: %.2f ms/step wall (CPU %.2f), solve %.2f ms/step, %.2f CG its/step; load %.2f -> "
                  "%.2f, others %.2f%s" % (r, NAMES[pre], rec["ms_per_step"], rec["cpu_ms_per_step"],
                                           rec["solve_ms_per_step"], rec["cg_iterations_per_step"], rec["loadavg_before"][0],
                                           rec["loadavg_after"][0], rec["other_cores"],
                                           " BUSY" if rec["busy"] else ""), flush=True)

    def stat(rs, key):
        v = [x[key] for x in rs]
        return {"min": min(v), "median": statistics.median(v), "max": max(v)}

    keys = ("ms_per_step", "cpu_ms_per_step", "solve_ms_per_step", "cg_iterations_per_step")
    out = {"benchmark": "precond_two_rooks", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "scene": "two_rooks", "scale": 1.0, "material": "Table 1 (E 5e8 Pa, nu 0.4, rho 700, viscosity 2.5e5 Pa s)",
           "viscous": "implicit, warm-started PCG, viscousTolerance %g" % w.core.viscousTolerance,
           "threads": a.threads, "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "(libgomp default)"),
           "tets": w.core.nTets, "pieces": w.core.nPieces, "dt": dt, "warmup_steps": a.warmup,
           "steps": a.steps, "rounds": a.rounds, "busy_rule": BUSY_RULE,
           "summary": {NAMES[p]: {k: stat(runs[p], k) for k in keys} for p in runs},
           "runs": {NAMES[p]: runs[p] for p in runs}}
    os.makedirs(os.path.dirname(a.log) or ".", exist_ok=True)
    with open(a.log, "w") as f:
        json.dump(out, f, indent=1)
    for p in runs:
        s = out["summary"][NAMES[p]]
        print("%-8s min/median: %.2f/%.2f ms/step, solve %.2f/%.2f ms/step, %.2f/%.2f CG its/step" % (
            NAMES[p], s["ms_per_step"]["min"], s["ms_per_step"]["median"], s["solve_ms_per_step"]["min"],
            s["solve_ms_per_step"]["median"], s["cg_iterations_per_step"]["min"],
            s["cg_iterations_per_step"]["median"]))


if __name__ == "__main__":
    main()
