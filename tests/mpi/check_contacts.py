"""Run by tests/python/test_mpi.py under mpiexec -n P: pieces in contact
across rank boundaries (tests/mpi/scenes.py withContacts: a block sliding
across the slab, cubes resting on it, crossed edges) on P ranks against the
same scene serially with 1 and 2 threads in rank 0's process.  Rank 0 prints
'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402
from qdem import _core  # noqa: E402

STEPS, CHUNK = int(os.environ.get("QDEM_MPI_STEPS", 400)), 25
comm = MPI.COMM_WORLD
KINDS = ("pointPolygon", "edgeEdge", "wall")
# The broad phase: 'triangles' (default) or the seed's cases 'A', 'B', 'C'
# (A and B also count the interior faces they test, after the kinds).
BROAD = os.environ.get("QDEM_MPI_BROADPHASE", "triangles")
if BROAD in ("A", "B"):
    KINDS = KINDS + ("interiorFaceTests", "interiorFaceNear")


REBALANCE = os.environ.get("QDEM_MPI_REBALANCE") == "1"
moved = []


def run(w, record, reduce):
    dt = 0.5 * w.stableDt()["combined"]
    for k in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)
        if REBALANCE and k == STEPS // CHUNK // 2 and w.core.mpiSize > 1:
            # Forced mid-run, contacts open: the split moves, histories with it.
            before = np.array(w.core.nodeOwner)
            w.core.rebalance()
            moved.append(int((np.array(w.core.nodeOwner) != before).sum()))
        counts = [w.core.contactCounts[k] for k in KINDS]
        record.append(reduce(counts[:3]) + [float(x) for x in w.core.obstacleReactions()[0][:3]] +
                      [w.core.energy["total"]] + reduce(counts[3:]))


def summed(counts):
    return [int(x) for x in comm.allreduce(np.array(counts), op=MPI.SUM)]


def build():
    w = scenes.withContacts()
    w.core.broadPhase = ("triangles", "A", "B", "C").index(BROAD)
    return w


dist = build()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
dist.core.rebalanceThreshold = 0  # (only the forced one, when asked)
series = []
run(dist, series, summed)
dist.core.gatherAll()
x, v = scenes.positions(dist)
stats = comm.gather(dist.core.partitionStats, root=0)
if comm.rank == 0:
    ref = {}
    for threads in (1, 2):
        _core.setThreads(threads)
        s = build()
        ss = []
        run(s, ss, lambda c: c)
        ref[threads] = (scenes.positions(s), ss)
    (xs, vs), sseries = ref[1]
    (x2, _), _ = ref[2]
    out = {"ranks": comm.size, "steps": STEPS, "maxDisplacement": float(np.abs(xs - x0).max()),
           "dx": float(np.abs(x - xs).max()), "dxThreads": float(np.abs(x2 - xs).max()),
           "series": series, "serialSeries": sseries,
           "ghosts": [s["ghosts"] for s in stats], "stepBytes": [s["stepBytes"] for s in stats],
           "stepMessages": [s["stepMessages"] for s in stats], "movedNodes": moved,
           "rebalances": [s["rebalances"] for s in stats]}
    print("RESULT " + json.dumps(out), flush=True)
