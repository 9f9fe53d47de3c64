"""Run by tests/python/test_mpi.py under mpiexec -n P: static friction holds
a cube across a rank boundary (tests/mpi/scenes.py frictionHold), as
serially.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402

comm = MPI.COMM_WORLD
STEPS = 3000


def run(w, cube):
    dt = 0.5 * w.stableDt()["combined"]
    x0 = cube.centroid.copy()
    w.core.step(dt, STEPS // 2)
    w.core.gatherAll()
    xMid = cube.centroid.copy()
    w.core.step(dt, STEPS // 2)
    w.core.gatherAll()
    return x0, xMid, cube.centroid.copy(), np.abs(cube.vel).max()


w, cube = scenes.frictionHold()
w.core.setCommunicator(comm)
x0, xm, x1, vmax = run(w, cube)
owners = np.array(w.core.nodeOwner)
slabRanks = sorted(set(owners[w.pieces[0].nodeSlice].tolist()))
if comm.rank == 0:
    s, scube = scenes.frictionHold()
    sx0, sxm, sx1, svmax = run(s, scube)
    print("RESULT " + json.dumps({"ranks": comm.size, "slabRanks": slabRanks, "x0": x0.tolist(), "xMid": xm.tolist(),
                                  "x1": x1.tolist(), "vmax": float(vmax), "serial": [sx0.tolist(), sxm.tolist(),
                                                                                     sx1.tolist()],
                                  "serialVmax": float(svmax)}), flush=True)
