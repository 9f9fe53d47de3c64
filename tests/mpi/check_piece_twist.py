"""Run by tests/python/test_piece_twist.py under mpiexec -n P: a cube
spinning on a slab, turned piece-piece springs sliding from triangle to
triangle across a rank boundary, on P ranks against the same scene serially
with 1 and 2 threads in rank 0's process.  Rank 0 prints 'RESULT {json}'.
Imported (no MPI) for the scene: spinningCube()."""
import json
import os
import sys

import numpy as np

import qdem
from qdem import _core

STEPS, CHUNK = int(os.environ.get("QDEM_MPI_STEPS", 1500)), 25


def spinningCube(spin=8.0):
    """A 6 cm cube spinning at `spin` rad/s about z set down on a slab lying
    on a floor (friction 0.5 everywhere), off the slab's middle so that the
    split cuts under it, a second cube stuck on the slab turning with it:
    point-polygon contacts with turned springs, sliding across the slab's
    triangles in torsion."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5,
                       frictionWall=0.5, frictionPiece=0.5)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.4, 0.2, 0.04), (10, 5, 1)), mat, pos=(0, 0, 0.024))
    top = 0.044 + 2 * 0.004
    w.addPiece(qdem.boxMesh((0.06, 0.06, 0.06), (3, 3, 3)), mat, pos=(0.01, 0.0, top + 0.03 - 0.0005),
               angVel=(0, 0, spin))
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(-0.12, 0.02, top + 0.025 - 0.0005),
               ori=((0, 0, 1), 0.3), angVel=(0, 0, -0.5 * spin))
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    o.young, o.friction = 1e8, 0.5
    c = w.core
    c.gravity = (0, 0, -9.81)
    c.trackEnergy = True
    c.setObstacles([o])
    return w


def run(w):
    dt = 0.5 * w.stableDt()["combined"]
    n = 0
    for _ in range(STEPS // CHUNK):
        w.core.step(dt, CHUNK)
        n += w.core.contactCounts["pointPolygon"]
    return n


if __name__ == "__main__":
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    dist = spinningCube()
    x0 = np.array(dist.core.pos, copy=True)
    dist.core.setCommunicator(comm)
    dist.core.rebalanceThreshold = 0
    count = int(comm.allreduce(run(dist), op=MPI.SUM))
    dist.core.gatherAll()
    x, v = np.array(dist.core.pos, copy=True), np.array(dist.core.vel, copy=True)
    slabRanks = sorted(set(np.array(dist.core.nodeOwner)[dist.pieces[0].nodeSlice].tolist()))
    if comm.rank == 0:
        ref = {}
        for threads in (1, 2):
            _core.setThreads(threads)
            s = spinningCube()
            ns = run(s)
            ref[threads] = (np.array(s.core.pos, copy=True), np.array(s.core.vel, copy=True), ns)
        xs, vs, ns = ref[1]
        x2, v2, _ = ref[2]
        print("RESULT " + json.dumps({
            "ranks": comm.size, "count": count, "serialCount": ns, "slabRanks": slabRanks,
            "maxDisplacement": float(np.abs(xs - x0).max()), "dx": float(np.abs(x - xs).max()),
            "dv": float(np.abs(v - vs).max()), "dxThreads": float(np.abs(x2 - xs).max()),
            "dvThreads": float(np.abs(v2 - vs).max()), "vmax": float(np.abs(vs).max())}), flush=True)
