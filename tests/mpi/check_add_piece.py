"""Run by tests/python/test_mpi.py under mpiexec -n P: a piece added mid-run
on every rank (the world is split again, every rank's state gathered first)
against the same run serially.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qdem  # noqa: E402
import scenes  # noqa: E402

comm = MPI.COMM_WORLD


def run(w, dist):
    if dist:
        w.core.setCommunicator(comm)
    dt = 0.5 * w.stableDt()["combined"]
    w.core.step(dt, 150)
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5,
                       frictionPiece=0.5)
    w.addPiece(qdem.boxMesh((0.04, 0.04, 0.04), (2, 2, 2)), mat, pos=(0.0, 0.05, 0.09), vel=(0, 0, -0.5))
    w.core.step(dt, 250)
    w.core.gatherAll()
    return np.array(w.core.pos), w.core.energy["total"]


x, e = run(scenes.withContacts(), True)
if comm.rank == 0:
    xs, es = run(scenes.withContacts(), False)
    x0 = scenes.withContacts().core.pos
    print("RESULT " + json.dumps({"ranks": comm.size, "dx": float(np.abs(x - xs).max()),
                                  "disp": float(np.abs(xs[:len(x0)] - x0).max()), "energy": [e, es]}), flush=True)
