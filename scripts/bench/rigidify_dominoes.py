"""What adaptive rigidity costs in accuracy on a short domino line of
bricks (doc/dev/performance_notebook.md, "Adaptive rigidity"): the same line
run all deformable and with rigidify (rigidWakeStrain 0, i.e. the relative
load test alone, and the given values), each piece's fall time, the order of
the falls, the front speed, the switches and the CPU time.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/rigidify_dominoes.py \\
        [--count 5] [--cells 2,6,12] [--young 1e8] [--duration 1.5] [--threads 2] [--rate 0.5] [--dwell 0.005] \\
        [--wakeStrains 0,1e-5,1e-4] [--log bench/logs/rigidify_dominoes_<date>.json]
    ... scripts/bench/rigidify_dominoes.py --table bench/logs/rigidify_dominoes_<date>.json   (its Markdown table)

Bricks 2 x 6 x 12 cm (thickness, width, height; --cells, 6 tets a cell), density
1000 kg/m^3, Poisson 0.3, no viscosity, restitution 0.5, particle radius
2 mm, friction 0.5 on the floor and 0.3 between bricks, 8 cm apart (centre
to centre) along x; the first tipped toward the second with 3 rad/s about
its front bottom edge.  A brick has fallen when its centre is below 70 % of
its height at rest; the front speed is the distance from the first to the
last fallen brick over the time between their falls.  Steps at 0.8 of the
stable step.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import qdem
from qdem import _core

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from benchutil import floorAndGravity  # noqa: E402

G = 9.81
T, W, H, GAP = 0.02, 0.06, 0.12, 0.08


def run(a, rigid, wakeStrain):
    w = qdem.World()
    mat = qdem.QdemMat(young=a.young, poisson=0.3, density=1000.0, viscosity=0.0, radius=2e-3, restitution=0.5,
                       frictionWall=0.5, frictionPiece=0.3)
    bricks = [w.addPiece(qdem.boxMesh((T, W, H), tuple(int(c) for c in a.cells.split(","))), mat, pos=(i * GAP, 0, H / 2 + mat.radius))
              for i in range(a.count)]
    floorAndGravity(w, G)
    w.core.rigidStrainRate, w.core.rigidTime = a.rate, a.dwell
    w.core.rigidWakeStrain = wakeStrain
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.02 / dt))         # settled under gravity
    b = bricks[0]
    x = b._nodes("pos")
    r = x - np.array([T / 2, 0, x[:, 2].min()])
    b.vel[:] = np.cross([0, a.tip, 0], r)
    w.core.rigidify = rigid
    z0 = [p.centroid[2] for p in bricks]
    fallen = [None] * a.count
    t0, cpu0 = w.core.time, time.process_time()
    steps = rigidSteps = 0
    while w.core.time - t0 < a.duration and any(f is None for f in fallen):
        w.core.step(dt, 20)
        steps += 20
        rigidSteps += 20 * w.core.nRigid
        for i, p in enumerate(bricks):
            if fallen[i] is None and p.centroid[2] < 0.7 * z0[i]:
                fallen[i] = w.core.time - t0
    done = [i for i in range(a.count) if fallen[i] is not None]
    order = sorted(done, key=lambda i: fallen[i])
    speed = ((order[-1] - order[0]) * GAP / (fallen[order[-1]] - fallen[order[0]])
             if len(order) > 1 and fallen[order[-1]] > fallen[order[0]] else None)
    return {"rigidify": rigid, "rigidWakeStrain": wakeStrain, "dt_s": dt, "steps": steps,
            "cpu_s": time.process_time() - cpu0, "fallen_s": fallen, "fall_order": order,
            "front_speed_m_s": speed, "rigidSwitches": w.core.rigidSwitches,
            "rigid_share": rigidSteps / max(1, steps * a.count),
            "centroids_m": [list(map(float, p.centroid)) for p in bricks]}


def table(log):
    """The Markdown table of a log this script wrote (doc/dev/performance_notebook.md)."""
    d = json.load(open(log))
    ref = d["deformable"]
    fmt = lambda v: "-" if v is None else "%.3f" % v  # noqa: E731
    text = ("| run | switches | rigid share | fall times [s] (brick 0, 1, ...) | fall order | front speed [m/s] | "
            "CPU s | speed-up |\n|---|---|---|---|---|---|---|---|\n")
    text += "| deformable | 0 | 0 | %s | %s | %s | %.1f | 1 |\n" % (
        ", ".join(fmt(v) for v in ref["fallen_s"]), ref["fall_order"], fmt(ref["front_speed_m_s"]), ref["cpu_s"])
    for r in d["rigid"]:
        text += "| rigidify, rigidWakeStrain %g | %d | %.2f | %s | %s | %s | %.1f | %.2f |\n" % (
            r["rigidWakeStrain"], r["rigidSwitches"], r["rigid_share"], ", ".join(fmt(v) for v in r["fallen_s"]),
            r["fall_order"], fmt(r["front_speed_m_s"]), r["cpu_s"], r["speedup_cpu"])
    a = d["args"]
    text += ("\n(`%s`, %s: %d bricks, cells %s, E %g Pa, rigidStrainRate %g /s, rigidTime %g s, %d threads, "
             "load %.1f before, %.1f after)\n" % (log, d["date"], a["count"], a["cells"], a["young"], a["rate"],
                                                  a["dwell"], a["threads"], d["load_before"][0], d["load_after"][0]))
    return text


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--table":
        print(table(sys.argv[2]))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=5)
    ap.add_argument("--cells", default="2,6,12", help="cells of a brick's mesh (thickness, width, height)")
    ap.add_argument("--young", type=float, default=1e8)
    ap.add_argument("--duration", type=float, default=1.5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rate", type=float, default=0.5)
    ap.add_argument("--dwell", type=float, default=0.005)
    ap.add_argument("--tip", type=float, default=3.0, help="the first brick's angular velocity [rad/s]")
    ap.add_argument("--wakeStrains", default="0,1e-5,1e-4")
    ap.add_argument("--log", default=None)
    a = ap.parse_args()
    _core.setThreads(a.threads)
    out = {"benchmark": "rigidify_dominoes", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "args": vars(a), "load_before": os.getloadavg()}
    out["deformable"] = ref = run(a, False, 0.0)
    print(json.dumps(ref), flush=True)
    out["rigid"] = []
    for s in (float(x) for x in a.wakeStrains.split(",")):
        r = run(a, True, s)
        r["fall_time_error_s"] = [None if x is None or y is None else y - x
                                  for x, y in zip(ref["fallen_s"], r["fallen_s"])]
        r["speedup_cpu"] = ref["cpu_s"] / r["cpu_s"] if r["cpu_s"] > 0 else None
        out["rigid"].append(r)
        print(json.dumps(r), flush=True)
    out["load_after"] = os.getloadavg()
    log = a.log or "bench/logs/rigidify_dominoes_%s.json" % time.strftime("%Y-%m-%d", time.gmtime())
    os.makedirs(os.path.dirname(log), exist_ok=True)
    with open(log, "w") as f:
        json.dump(out, f, indent=1)
    print("rigidify dominoes -> %s" % log)


if __name__ == "__main__":
    main()
