"""The former bench_shogi.py's measurements (run(), sleeping(): the core stepped
directly, 200 steps before any hit; kept here so that the issue-13 sittings
stay comparable; bench_shogi.py now times QdemEngine through the first hits) with the piece meshes and
the Table 1 scale read from a cache instead of re-meshed with CGAL in every
process (meshing is ~55 s of a ~60 s run and is not what is compared; both
builds then step the very same meshes).  Prints one JSON line.

    PYTHONPATH=<build>/python python3.11 arch_shogi_cached.py CACHE.npz STEPS [--make]
--make builds the cache (with the real shogi.mesh and stableScale)."""
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import qdem  # noqa: E402
from qdem import _core  # noqa: E402
from qdem.scenes import shogi  # noqa: E402
from qdem.mesh import Mesh  # noqa: E402

from benchutil import floorAndGravity, msPerStep  # noqa: E402


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



cache, steps = sys.argv[1], int(sys.argv[2])
if "--make" in sys.argv:
    _core.setThreads(2)
    scale = math.ceil(shogi.stableScale(qdem.QdemMat()))
    d = {"scale": np.array(scale)}
    for k in shogi.ORDER:
        m = shogi.mesh(k)
        d[k + "_nodes"], d[k + "_tets"] = m.nodes, m.tets
    np.savez(cache, **d)
    print(json.dumps({"scale": scale, "kinds": list(shogi.ORDER)}))
    sys.exit(0)

d = np.load(cache)
meshes = {k: Mesh(d[k + "_nodes"], d[k + "_tets"], check=False) for k in shogi.ORDER}
shogi.mesh = lambda kind, *a, **kw: meshes[kind]
scale = int(d["scale"])
_core.setThreads(2)
res = {"scenes": {}, "table1_scale": scale, "steps": steps}
for name in shogi.SCENES:
    res["scenes"][name] = run(name, steps, scale)
res["sleeping"] = sleeping(steps, scale)
print(json.dumps(res))
