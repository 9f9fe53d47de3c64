"""Run by tests/python/test_mpi_contact_step.py under mpiexec -n P: the
run-time stable step of the piece-piece contacts as they are (ContactLoad.hpp)
on a world split over the ranks, against the serial world: (a) two soft cubes
pressed face to face report the same limit, node and piece on every rank as
serially; (b) two soft cubes thrown at each other at 0.9 of the stable step
before the run stop in the same step with the same message on every rank as
serially (the contacts as they are lower the limit below O.dt); (c) the
sleeping scene of check_sleep.py, pieces falling asleep beside awake ones:
the same limit as serially after 450 steps (a sleeping piece's rows are not
cleared each step and were summed into its nodes' loads under MPI, which
grew until the run stopped at step 399).  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

from mpi4py import MPI

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "python"))
import qdem  # noqa: E402
from conftest import rubber  # noqa: E402

comm = MPI.COMM_WORLD
KEYS = ("pieceContact", "pieceContactNode", "pieceContactPiece", "combined")


def pressed():
    """Two 3-cell cubes face to face, node on node, their springs half pressed
    (a reach of 2 x 3 cm over 3.3 cm cells: each face node is pressed and
    carries the other piece's nodes on its triangles)."""
    r, L = 0.03, 0.1
    mat = rubber(radius=r, restitution=1.0)
    w = qdem.World()
    gap = r
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(-L / 2 - gap / 2, 0, 0))
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(L / 2 + gap / 2, 0.004, 0.002))
    return w


def thrown():
    """Two soft 3-cell cubes 1 cm apart closing at 2 m/s, offset across."""
    r, L = 0.02, 0.1
    mat = rubber(radius=r, restitution=0.5)
    w = qdem.World()
    gap = 2 * r + 0.01
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(-L / 2 - gap / 2, 0, 0), vel=(1.0, 0, 0))
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(L / 2 + gap / 2, 0.01, 0.005), vel=(-1.0, 0, 0))
    return w


def limitReport(w, split):
    if split:
        w.core.setCommunicator(comm)
    w.core.step(1e-9 * w.stableDt()["combined"], 1)
    d = w.stableDt()
    return {k: d[k] for k in KEYS}


def stop(w, split):
    dt = 0.9 * w.stableDt()["combined"]
    if split:
        w.core.setCommunicator(comm)
    try:
        w.core.step(dt, 400)
    except qdem.StabilityError as e:
        return {"stopped": True, "message": str(e), "iter": int(w.core.iter), "dt": dt}
    return {"stopped": False, "message": "", "iter": int(w.core.iter), "dt": dt}


def sleeping(split):
    sys.path.insert(0, HERE)
    import scenes
    w = scenes.withContacts()
    w.core.sleepVelocity = 0.02
    w.core.sleepTime = 0.005
    w.core.localDamping = 0.3
    dt = 0.5 * w.stableDt()["combined"]
    if split:
        w.core.setCommunicator(comm)
    try:
        w.core.step(dt, 450)
    except qdem.StabilityError as e:
        return {"stopped": int(w.core.iter), "message": str(e)}
    d = w.stableDt()
    return dict({k: d[k] for k in KEYS}, asleep=int(w.core.nAsleep))


out = {"rank": comm.rank, "limit": limitReport(pressed(), True), "stop": stop(thrown(), True),
       "sleeping": sleeping(True)}
everything = comm.gather(out, root=0)
if comm.rank == 0:
    from qdem import _core
    _core.setThreads(1)
    serial = {"limit": limitReport(pressed(), False), "stop": stop(thrown(), False), "sleeping": sleeping(False)}
    print("RESULT " + json.dumps({"ranks": comm.size, "perRank": everything, "serial": serial}), flush=True)
