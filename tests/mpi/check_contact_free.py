"""Run by tests/python/test_mpi.py under mpiexec -n P: the contact-free scene
(tests/mpi/scenes.py) on P ranks against the same scene stepped serially in
rank 0's process.  Rank 0 prints one line 'RESULT {json}'."""
import json
import sys
import os

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenes  # noqa: E402

STEPS, CHUNK = 1000, 50
comm = MPI.COMM_WORLD


def run(w, record):
    dt = 0.5 * w.stableDt()["combined"]
    for _ in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)
        record.append([float(x) for x in w.core.obstacleReactions()[0]] + [w.core.energy["total"],
                                                                            w.core.energy["kinetic"]])


dist = scenes.contactFree()
x0 = np.array(dist.core.pos, copy=True)
dist.core.setCommunicator(comm)
series = []
run(dist, series)
dist.core.gatherAll()
x, v = scenes.positions(dist)
stats = dist.core.partitionStats
owner = np.array(dist.core.nodeOwner)
# Every rank must hold the same split; each rank owns what the split says.
owners = comm.allgather(owner.tobytes())
counts = comm.allgather((stats["ownedNodes"], stats["ownedTets"], stats["ghosts"], stats["neighbours"]))
if comm.rank == 0:
    ser = scenes.contactFree()
    sseries = []
    run(ser, sseries)
    xs, vs = scenes.positions(ser)
    disp = float(np.abs(xs - x0).max())
    out = {
        "ranks": comm.size,
        "maxDisplacement": disp,
        "dx": float(np.abs(x - xs).max()),
        "dv": float(np.abs(v - vs).max()),
        "vmax": float(np.abs(vs).max()),
        "sameSplitEverywhere": all(o == owners[0] for o in owners),
        "ownedPerRank": [c[0] for c in counts],
        "ownedByOwnerArray": [int((owner == r).sum()) for r in range(comm.size)],
        "tetsPerRank": [c[1] for c in counts],
        "nNodes": int(len(owner)),
        "nTets": int(len(dist.core.tets)),
        "neighbours": [c[3] for c in counts],
        "imbalance": stats["imbalance"],
        # Momentum ledger: the same total momentum as serially.
        "momentum": (np.array(dist.core.mass)[:, None] * v).sum(axis=0).tolist(),
        "serialMomentum": (np.array(ser.core.mass)[:, None] * vs).sum(axis=0).tolist(),
        "series": series,
        "serialSeries": sseries,
    }
    print("RESULT " + json.dumps(out), flush=True)
