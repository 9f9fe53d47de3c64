"""Time to solution of the shogi scenes (seed Figures 7-10): a short run of
each scene with the seed's Table 1 material at the length scale where Table 1's
time step (6.4e-6 s) is stable, reported as wall seconds per simulated second
on this machine (2 threads), core stepping only (no YADE engine overhead).

    /usr/bin/python3.11 scripts/bench/bench_shogi.py [--steps 200] [--out out/bench]
"""
import argparse
import json
import math
import os

import qdem
from qdem import _core, shogi

from benchutil import floorAndGravity, msPerStep


def run(name, steps, scale):
    w = qdem.World()
    mat = qdem.QdemMat()
    pieces = shogi.scene(name, mat, scale, world=w)
    floorAndGravity(w)
    dt = 6.4e-6
    w.core.checkDt(dt)
    wall = 1e-3 * msPerStep(w, steps, dt, warmup=5) * steps
    return {"pieces": len(pieces), "tets": w.core.nTets, "nodes": w.core.nNodes, "scale": scale, "dt": dt,
            "stable_dt": w.stableDt()["combined"], "steps": steps,
            "ms_per_step": 1e3 * wall / steps, "wall_s_per_simulated_s": wall / (steps * dt)}


def sleeping(steps, scale):
    """The 40-piece line with sleeping pieces (doc/sleeping.md): sleeping on
    but all pieces awake (the bookkeeping's cost), then 39 of 40 asleep while
    the first one falls (what a domino run costs between hits)."""
    import numpy as np
    w = qdem.World()
    mat = qdem.QdemMat()
    pieces = shogi.scene("forty", mat, scale, world=w, push=0.0)
    floorAndGravity(w)
    dt = 6.4e-6
    w.core.sleepVelocity = 1e3  # everything counts as slow ...
    w.core.sleepTime = 1e3      # ... but nothing sleeps yet
    awake = msPerStep(w, steps, dt, warmup=5)
    w.core.sleepTime = 0.0
    w.core.step(dt, 2)
    assert w.core.nAsleep == len(pieces)
    w.core.sleepVelocity = 1e-3
    pieces[0].vel[:] = np.cross([0.0, 0.6, 0.0], pieces[0].pos - [0.0, 0.0, mat.radius])
    asleep = msPerStep(w, steps, dt, warmup=5)
    return {"ms_per_step_sleep_on_all_awake": awake, "ms_per_step_39_asleep": asleep,
            "asleep": w.core.nAsleep, "pieces": len(pieces)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    _core.setThreads(2)
    scale = math.ceil(shogi.stableScale(qdem.QdemMat()))
    res = {"scenes": {}, "threads": 2, "table1_scale": scale}
    for name in shogi.SCENES:
        res["scenes"][name] = run(name, a.steps, scale)
        r = res["scenes"][name]
        print("shogi %-10s: %d pieces, %d tets, %.2f ms/step, %.0f s wall per simulated s"
              % (name, r["pieces"], r["tets"], r["ms_per_step"], r["wall_s_per_simulated_s"]), flush=True)
    res["sleeping"] = sleeping(a.steps, scale)
    r = res["sleeping"]
    print("shogi forty, sleeping on: %.2f ms/step all awake, %.2f ms/step with %d of %d asleep"
          % (r["ms_per_step_sleep_on_all_awake"], r["ms_per_step_39_asleep"], r["asleep"], r["pieces"]), flush=True)
    json.dump(res, open(os.path.join(a.out, "shogi.json"), "w"), indent=2)


if __name__ == "__main__":
    main()
