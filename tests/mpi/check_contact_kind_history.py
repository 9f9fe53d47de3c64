"""Run by tests/python/test_mpi_contact_kind_history.py under mpiexec -n P:
the test-only contact kind with history (nodeSpringTest, a bond between
surface nodes of different pieces: pkg/phases/NodeSpringKind.cpp) alone, in
tests/mpi/scenes.py withContacts without gravity (a cube sliding across the
slab bonds to its nodes and tears the bonds as it goes; a cube falls onto
crossed edges), on P ranks with the contact halo and a forced rebalance
mid-run (the bonds move with their nodes), against the same run serially in
rank 0's process.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402
from qdem import _core  # noqa: E402

STEPS, CHUNK = 400, 25
comm = MPI.COMM_WORLD
moved = []


def build():
    w = scenes.withContacts()
    c = w.core
    c.pointPolygonOn = False
    c.edgeEdgeOn = False
    c.nodeSpringTestOn = True
    c.gravity = (0, 0, 0)
    return w


def run(w, record, reduce):
    dt = 0.5 * w.stableDt()["combined"]
    for k in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)
        if k == STEPS // CHUNK // 2 and w.core.mpiSize > 1:
            before = np.array(w.core.nodeOwner)
            w.core.rebalance()  # bonds open: their rows move with their nodes
            moved.append(int((np.array(w.core.nodeOwner) != before).sum()))
        record.append(reduce(w.core.contactCounts["nodeSpringTest"]))


dist = build()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
dist.core.rebalanceThreshold = 0  # (only the forced one)
series = []
run(dist, series, lambda n: int(comm.allreduce(n, op=MPI.SUM)))
dist.core.gatherAll()
x, _ = scenes.positions(dist)
stats = comm.gather(dist.core.partitionStats, root=0)
if comm.rank == 0:
    _core.setThreads(1)
    s = build()
    sseries = []
    run(s, sseries, int)
    xs, _ = scenes.positions(s)
    out = {"ranks": comm.size, "maxDisplacement": float(np.abs(xs - x0).max()), "dx": float(np.abs(x - xs).max()),
           "series": series, "serialSeries": sseries, "ghosts": [st["ghosts"] for st in stats],
           "movedNodes": moved}
    print("RESULT " + json.dumps(out), flush=True)
