"""Run by tests/python/test_mpi.py under mpiexec -n P: implicit viscosity
(viscousIntegration='implicit') on a viscous deforming scene (the
contact-free pieces of tests/mpi/scenes.py falling on the floor, a
viscosity that makes the explicit viscous step ~40 times smaller than the
elastic one), on P ranks against the same scene serially with 1 and 2
threads in rank 0's process, at half the elastic limit: more than 10 times
the explicit viscous one.
Every rank records the conjugate gradients' iteration count of every step.
Argument 'warm': viscousWarmStart on (each solve starts from the last step's
change); otherwise off (from zero: results depend on the state alone).
Argument 'jacobi': the Jacobi preconditioner; otherwise the co-rotated
Cholesky one (its split pieces gathered: the serial preconditioner).
Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402
from qdem import _core  # noqa: E402

STEPS = int(os.environ.get("QDEM_MPI_STEPS", 300))
CHUNK = 25
VISCOSITY = 4000.0  # [Pa s]: the explicit viscous limit ~1/40 of the elastic one
WARM = "warm" in sys.argv[1:]
# The preconditioner: 'jacobi' or 'cholesky' (the default) among the arguments.
PRECONDITIONER = 0 if "jacobi" in sys.argv[1:] else 1
comm = MPI.COMM_WORLD


def build():
    w = scenes.contactFree(viscosity=VISCOSITY)
    w.core.viscousIntegration = 1
    w.core.viscousWarmStart = WARM
    w.core.viscousPreconditioner = PRECONDITIONER
    return w


moved = []


def run(w, iterations, series):
    limits = w.stableDt()
    dt = 0.5 * limits["combinedImplicit"]
    assert dt > 10 * limits["combinedExplicit"], limits  # explicit viscosity could not take this step
    for k in range(STEPS):
        if WARM and k == STEPS // 2 and w.core.mpiSize > 1:
            # A rebalance forced mid-run: the warm start's rows move with the
            # nodes (a lost or misplaced row would start that solve cold).
            # (every piece split along the curve now, so that the split moves)
            before = np.array(w.core.nodeOwner)
            w.core.partitionWholePieceFraction = 0.0
            w.core.rebalance()
            moved.append(int((np.array(w.core.nodeOwner) != before).sum()))
        w.core.step(dt, 1)
        iterations.append(int(w.core.counts["viscousIterations"]))
        if (k + 1) % CHUNK == 0:
            e = w.core.energy
            series.append([float(x) for x in w.core.obstacleReactions()[0][:3]] + [e["total"], e["viscous"],
                                                                                  e["kinetic"]])
    return limits


dist = build()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
its, series = [], []
limits = run(dist, its, series)
dist.core.gatherAll()
x, v = scenes.positions(dist)
allIts = comm.gather(its, root=0)
owned = comm.gather(dist.core.partitionStats["ownedTets"], root=0)
if comm.rank == 0:
    ref = {}
    for threads in (1, 2):
        _core.setThreads(threads)
        s = build()
        si, ss = [], []
        run(s, si, ss)
        ref[threads] = (scenes.positions(s), si, ss, s)
    (xs, vs), sIts, sseries, ser = ref[1]
    (x2, v2), _, sseries2, ser2 = ref[2]
    out = {"ranks": comm.size, "steps": STEPS, "limits": {k: v_ for k, v_ in limits.items() if k != "limitedBy"},
           "maxDisplacement": float(np.abs(xs - x0).max()),
           "dx": float(np.abs(x - xs).max()), "dxThreads": float(np.abs(x2 - xs).max()),
           "dv": float(np.abs(v - vs).max()), "dvThreads": float(np.abs(v2 - vs).max()),
           "vmax": float(np.abs(vs).max()), "iterations": allIts, "serialIterations": sIts,
           "ownedTets": owned, "series": series, "serialSeries": sseries,
           "serialSeries2Threads": sseries2, "warm": WARM, "moved": moved,
           "momentum": (np.array(dist.core.mass)[:, None] * v).sum(axis=0).tolist(),
           "serialMomentum": (np.array(ser.core.mass)[:, None] * vs).sum(axis=0).tolist(),
           "preconditioner": PRECONDITIONER, "serialMomentum2Threads": (np.array(ser2.core.mass)[:, None] * v2).sum(axis=0).tolist()}
    print("RESULT " + json.dumps(out), flush=True)
