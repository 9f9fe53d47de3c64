"""Run by tests/python/test_mass_scaling.py under mpiexec -n 2: a sliver block
with selective mass scaling (addPiece(targetDt=...)) dropped on a floor next
to a plain block, pieces in contact across the split, on the ranks against
the same scene stepped serially in rank 0's process.  Rank 0 prints one line
'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "python"))
import scenes  # noqa: E402
import qdem  # noqa: E402
from test_mass_scaling import MAT, sliverMesh  # noqa: E402

STEPS, CHUNK = 1200, 100
comm = MPI.COMM_WORLD


def build():
    mat = qdem.QdemMat(**dict(MAT, restitution=0.5, frictionWall=0.4, frictionPiece=0.3))
    probe = qdem.World()
    probe.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), mat)
    target = 0.5 * probe.stableDt()["viscous"]
    w = qdem.World()
    x, t = sliverMesh()
    w.addPiece((x, t), mat, pos=(0, 0, 0.06), vel=(0.5, 0, -0.3), targetDt=target, maxAddedMass=0.05)
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), mat, pos=(0.13, 0.02, 0.055))
    w.core.gravity = (0, 0, -9.81)
    w.core.setObstacles([scenes.floor(young=0.0)])
    return w


def run(w):
    dt = 0.8 * w.stableDt()["combined"]
    for _ in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)


dist = build()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
run(dist)
dist.core.gatherAll()
x, v = scenes.positions(dist)
if comm.rank == 0:
    ser = build()
    run(ser)
    xs, vs = scenes.positions(ser)
    out = {
        "addedMass": ser.pieces[0].addedMass,
        "massEqual": bool(np.array_equal(np.array(dist.core.mass), np.array(ser.core.mass))),
        "maxDisplacement": float(np.abs(xs - x0).max()),
        "dx": float(np.abs(x - xs).max()),
        "dv": float(np.abs(v - vs).max()),
        "vmax": float(np.abs(vs).max()),
        "contacts": dist.core.contactCounts["pointPolygon"],
    }
    print("RESULT " + json.dumps(out), flush=True)
