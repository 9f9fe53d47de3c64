"""What a step of a long two-rooks run costs where the run is, not at its
start (doc/shogi.md, "Toward real size"): scripts/shogi/scales.py times
short runs from rest, whose first few hundred implicit steps are a
transient (the overdamped sag under sudden gravity) with several times the
conjugate-gradient iterations of the rest of the run.

    PYTHONPATH=build/python OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/shogi/cost_in_run.py \
        out/shogi/two_rooks_mu0.1_table1_x1_implicit [more run directories] [--steps 300] [--rounds 3] \
        [--log bench/logs/shogi_cost_in_run_<date>.json]

For each run directory of scripts/shogi/domino.py (its checkpoint.npz and
hits.json), the scene is built as scales.py builds it (bare core world, the
floor as stiff as domino.py's), the checkpoint loaded twice, and the two
copies stepped on one thread, interleaved `rounds` times `steps` steps:
implicit viscosity with each solve started from the last step's change (the
default) and from zero (viscousWarmStart=False).  CPU milliseconds per step
(one thread: the wall time on a quiet core) and CG iterations per step,
medians over the rounds.
"""
import argparse
import json
import os
import statistics
import sys

import qdem
from qdem import _core
from qdem.scenes import shogi

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scales import G, cpuMsPerStep, floorAndGravity, table1Scale  # noqa: E402


def build(run, stable, warm):
    w = qdem.World()
    mat = qdem.QdemMat(frictionPiece=run["frictionPiece"], radius=qdem.QdemMat().radius * run["scale"] / stable)
    shogi.scene("two_rooks", mat, run["scale"], world=w)
    floorAndGravity(w, G, young=max(1e7, mat.young))  # the floor as domino.py's
    w.core.viscousIntegration = 1
    w.core.viscousWarmStart = warm
    return w


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="+", help="domino.py output directories (checkpoint.npz, hits.json)")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--log", default=None)
    a = ap.parse_args()
    _core.setThreads(1)
    stable = table1Scale()
    out = {"steps": a.steps, "rounds": a.rounds, "threads": 1, "runs": {}}
    for d in a.runs:
        with open(os.path.join(d, "hits.json")) as f:
            run = json.load(f)
        worlds = {}
        for name, warm in (("warm", True), ("from_zero", False)):
            w = build(run, stable, warm)
            qdem.loadState(os.path.join(d, "checkpoint.npz"), world=w)
            worlds[name] = w
        t0 = worlds["warm"].core.time
        samples = {name: [] for name in worlds}
        for _ in range(a.rounds):  # interleaved: both see the same machine load
            for name, w in worlds.items():
                samples[name].append(cpuMsPerStep(w, run["dt"], a.steps))
        r = {"scale": run["scale"], "frictionPiece": run["frictionPiece"], "dt": run["dt"], "from_s": t0,
             "tets": worlds["warm"].core.nTets}
        for name, s in samples.items():
            r[name] = {"cpu_ms_per_step": statistics.median(x[0] for x in s),
                       "cg_iterations_per_step": statistics.median(x[1] for x in s),
                       "samples": [list(x) for x in s]}
        r["from_zero_over_warm"] = r["from_zero"]["cpu_ms_per_step"] / r["warm"]["cpu_ms_per_step"]
        out["runs"][os.path.basename(os.path.normpath(d))] = r
        print("%s from t = %.4g s: warm %.2f ms/step (%.1f CG its), from zero %.2f ms/step (%.1f), ratio %.2f" % (
            os.path.basename(os.path.normpath(d)), t0, r["warm"]["cpu_ms_per_step"],
            r["warm"]["cg_iterations_per_step"], r["from_zero"]["cpu_ms_per_step"],
            r["from_zero"]["cg_iterations_per_step"], r["from_zero_over_warm"]), flush=True)
    if a.log:
        os.makedirs(os.path.dirname(a.log) or ".", exist_ok=True)
        with open(a.log, "w") as f:
            json.dump(out, f, indent=2)


if __name__ == "__main__":
    main()
