"""Run by tests/python/test_mpi_error_agreement.py under mpiexec -n P: an
error raised on one rank only, in a step whose later phases hold collectives
(the sleep phase's reductions, the implicit viscous solve's sums), stops
every rank within seconds with the failing rank's message.  Each case's
error arises on the rank(s) owning the nodes concerned; the other ranks go
on into those collectives.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys
import time

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qdem  # noqa: E402
import scenes  # noqa: E402

comm = MPI.COMM_WORLD
last = comm.size - 1


def caught(f):
    """(error type, message, seconds to raise it) on this rank."""
    t0 = time.time()
    try:
        f()
    except Exception as e:  # noqa: BLE001 - the test reports the type
        return type(e).__name__, str(e), time.time() - t0
    return None, "", time.time() - t0


def sleepy(w):
    w.core.sleepVelocity = 0.02
    w.core.sleepTime = 0.005
    return w


def throughFloor(w):
    """A small cube 3 cm through the floor, far along x: the start-overlap
    refusal of the obstacle phase, on the rank owning its nodes (with
    implicit viscosity: the others find none of them)."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, radius=0.004)
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.6, 0.6, 0.0))
    return w


out = {"rank": comm.rank}
cases = sys.argv[1:] or ["sleepNan", "implicitOverlap"]  # (one at a time: to see which hangs)
dt = 0.5 * scenes.contactFree().stableDt()["combined"]


def sleepNan():
    """A NaN velocity on a node of the last rank: its integration fails, the
    sleep phase's reduction after it."""
    w = sleepy(scenes.contactFree())
    w.core.setCommunicator(comm)
    w.core.step(dt, 3)
    node = int(np.nonzero(np.array(w.core.nodeOwner) == last)[0][0])
    if comm.rank == last:
        w.core.vel[node, 0] = float("nan")
    return caught(lambda: w.core.step(dt, 2))


def implicitOverlap():
    """The obstacle-phase error with implicit viscosity: the integration's
    solve (sums over every rank) after it."""
    w = throughFloor(scenes.contactFree(viscosity=50.0))
    w.core.viscousIntegration = 1
    w.core.setCommunicator(comm)
    return caught(lambda: w.core.step(dt, 5))


for case in cases:
    out[case] = globals()[case]()

everything = comm.gather(out, root=0)
if comm.rank == 0:
    print("RESULT " + json.dumps({"ranks": comm.size, "caught": everything}), flush=True)
