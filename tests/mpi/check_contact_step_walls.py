"""Run by tests/python/test_mpi_contact_step_walls.py under mpiexec -n P: the
run-time stable step with walls in the node loads (ContactLoad.hpp) on a
world split over the ranks, against the serial world: two soft cubes pressed
side by side on a floor, their facing sides' bottom nodes carrying the
floor's springs and the other cube's.  Each node's floor contact is counted
by its owner alone.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "python"))
import qdem  # noqa: E402
from conftest import rubber  # noqa: E402

comm = MPI.COMM_WORLD
KEYS = ("pieceContact", "pieceContactNode", "pieceContactPiece", "combined")


def squeezed():
    r, L = 0.03, 0.1
    mat = rubber(radius=r, restitution=1.0)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(-L / 2 - r / 2, 0, L / 2 + r / 2))
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(L / 2 + r / 2, 0.004, L / 2 + r / 2))
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    return w


def limitReport(split):
    w = squeezed()
    before = w.stableDt()["combined"]
    if split:
        w.core.setCommunicator(comm)
    w.core.step(1e-9 * before, 1)
    d = w.stableDt()
    out = {k: d[k] for k in KEYS}
    out["before"] = before
    return out


out = {"rank": comm.rank, "limit": limitReport(True)}
everything = comm.gather(out, root=0)
if comm.rank == 0:
    from qdem import _core
    _core.setThreads(1)
    print("RESULT " + json.dumps({"ranks": comm.size, "perRank": everything, "serial": {"limit": limitReport(False)}}),
          flush=True)
