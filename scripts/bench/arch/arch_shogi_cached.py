"""bench_shogi.py's measurements (run(), sleeping()) with the piece meshes and
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
from qdem import _core, shogi  # noqa: E402
from qdem.mesh import Mesh  # noqa: E402

import bench_shogi  # noqa: E402

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
    res["scenes"][name] = bench_shogi.run(name, steps, scale)
res["sleeping"] = bench_shogi.sleeping(steps, scale)
print(json.dumps(res))
