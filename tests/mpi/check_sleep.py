"""Run by tests/python/test_mpi.py under mpiexec -n P: sleeping pieces on P
ranks (the decisions taken alike on every rank from the ranks' largest
speeds and the whole pieces' boxes) against serial.  Rank 0 prints
'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402

comm = MPI.COMM_WORLD
STEPS, CHUNK = 3000, 100


def build():
    w = scenes.withContacts()
    w.core.sleepVelocity = 0.02
    w.core.sleepTime = 0.005
    w.core.localDamping = 0.3
    return w


def run(w):
    dt = 0.5 * w.stableDt()["combined"]
    out = []
    for _ in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)
        out.append([w.core.nAsleep, w.core.energy["total"], w.core.energy["sleep"]])
    return out


dist = build()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
series = run(dist)
dist.core.gatherAll()
x = np.array(dist.core.pos)
asleepEverywhere = comm.gather([dist.core.asleep(i) for i in range(dist.core.nPieces)], root=0)
if comm.rank == 0:
    from qdem import _core
    _core.setThreads(1)
    s = build()
    ss = run(s)
    xs = np.array(s.core.pos)
    print("RESULT " + json.dumps({"ranks": comm.size, "series": series, "serialSeries": ss,
                                  "disp": float(np.abs(xs - x0).max()), "dx": float(np.abs(x - xs).max()),
                                  "asleep": asleepEverywhere,
                                  "serialAsleep": [s.core.asleep(i) for i in range(s.core.nPieces)]}), flush=True)
