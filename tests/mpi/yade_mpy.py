"""YADE spheres (or a clump), a floor and a QDEM piece under YADE's own MPI
mode, yade.mpy: the same script serially (`yade -n -x tests/mpi/yade_mpy.py
SCENE`, where mp.mpirun falls back to O.run) and on P ranks
(`mpiexec -n P yade -n -x tests/mpi/yade_mpy.py SCENE`: mpy's master keeps
the floor, the workers the spheres, placed by qdem.yade.mpy.assignSubdomains
from QDEM's split).  test_mpi.py compares the two.

SCENE: 'drop' (twelve spheres falling on a block that rests on a floor) or
'clump' (a three-sphere clump thrown along a slab on a floor), the scenes of
tests/mpi/yade_spheres.py (the clump starting just out of contact).  QDEM_THREADS: QDEM's threads (the serial
1-vs-2-thread licence).  QDEM_MPY_RUN_FIRST=1: an O.run
before mp.mpirun (refused under mpy); QDEM_MPY_MERGE=1: mp.mergeScene()
at the end and a step on the master (refused).  Rank 0 writes the results as JSON to $QDEM_MPI_OUT
(else prints 'RESULT {json}')."""
import json
import os
import sys

import numpy as np
from yade import O, mpy as mp, utils
from yade.wrapper import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                          Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

import qdem

SCENE = sys.argv[1] if len(sys.argv) > 1 else "drop"
STEPS, CHUNK = int(os.environ.get("QDEM_MPI_STEPS", 1000)), 25
THREADS = int(os.environ.get("QDEM_THREADS", "1"))


def build():
    O.bodies.append(utils.wall(0, axis=2, sense=1))  # body 0: the floor
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
    if SCENE == "drop":
        mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.004,
                           restitution=0.1, frictionPiece=0.5)
        piece = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.045))
        movers = []
        for i in range(12):  # over the whole block
            x, y = -0.085 + 0.0155 * i, 0.03 * ((i % 3) - 1)
            b = O.bodies.append(utils.sphere((x, y, 0.098 + 0.003 * (i % 4)), 0.007, material=fm))
            O.bodies[b].state.vel = (0.05 * ((i % 2) * 2 - 1), 0, -0.3)
            movers.append(b)
        return piece, movers
    mat = qdem.QdemMat(young=5e6, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.003,
                       restitution=0.1, frictionPiece=0.6)
    piece = qdem.addPiece(qdem.boxMesh((0.3, 0.12, 0.03), (12, 5, 2)), mat, pos=(0, 0, 0.018))
    top = 0.033 + 0.003
    # (0.3 mm above the slab's reach: serially, spheres are listed by the collider from the second step on)
    parts = [utils.sphere((0.0 + dx, dz * 0.5, top + 0.0103 + dz), r, material=fm)
             for dx, dz, r in ((0.0, 0.0, 0.01), (0.014, 0.004, 0.008), (-0.012, 0.006, 0.007))]
    clumpId, members = O.bodies.appendClumped(parts)
    O.bodies[clumpId].state.vel = (1.5, 0.0, -0.3)
    O.bodies[clumpId].state.angVel = (0.0, 0.0, 2.0)
    return piece, [clumpId]


O.trackEnergy = True
piece, movers = build()
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
             qdem.QdemEngine(label="qe", threads=THREADS), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
O.dt = 0.8 * qe.stableTimeStep()  # noqa: F821 - YADE's label
if os.environ.get("QDEM_MPY_RUN_FIRST") == "1":
    O.run(1, True)  # refused under yade.mpy (test_mpi.py): QDEM steps with mp.mpirun there
placed = qdem.yade.mpy.assignSubdomains()  # spheres to the workers owning the surface near them ({} serially)
core = qdem.defaultWorld().core
x0 = np.array(core.pos, copy=True)
series, mine = [], 0
for chunk in range(STEPS // CHUNK):
    mp.mpirun(CHUNK)  # O.run(CHUNK, True) serially
    counts = qdem.mpi.summedCounts(core)
    mine += core.contactCounts["sphere"]  # computed on this rank (the chunk's last step)
    floor = list(O.forces.f(0)) if O.bodies[0] is not None else [0.0] * 3  # (the floor lives on mpy's master)
    series.append([counts["sphere"]] + floor + [core.energy["total"]])


def owned():
    """{id: pos + vel + angVel} of the movers this rank integrates."""
    here = {}
    for b in movers:
        body = O.bodies[b] if b < len(O.bodies) else None
        if body is not None and (mp.numThreads in (None, 1) or body.subdomain == mp.rank):
            s = body.state
            here[b] = list(s.pos) + list(s.vel) + list(s.angVel)
    return here


states, ranks = owned(), (mp.numThreads or 1)
out = {"ranks": ranks, "qdemRanks": core.mpiSize, "threads": THREADS, "series": series,
       "pos": np.array(core.pos).tolist(), "disp": float(np.abs(np.array(core.pos) - x0).max()),
       "placed": {str(k): v for k, v in placed.items()}, "iter": core.iter}
if ranks > 1:
    from mpi4py import MPI
    every = MPI.COMM_WORLD.allgather(states)
    states = {k: v for e in every for k, v in e.items()}
    out["owners"] = [sorted(e) for e in every]
    out["sphereContactsPerRank"] = MPI.COMM_WORLD.allgather(mine)
    out["ownedNodes"] = MPI.COMM_WORLD.allgather(core.partitionStats.get("ownedNodes", 0))
    # wall time of the mpy layer (gather, forces back; sphere-contact phase included) per step, per rank
    out["layerSecondsPerStep"] = MPI.COMM_WORLD.allgather(qe.sphereCouplingTime() / max(core.iter, 1))  # noqa: F821
out["spheres"] = [states[b] for b in movers]
if os.environ.get("QDEM_MPY_MERGE") == "1" and ranks > 1:
    mp.mergeScene()  # collective: the master gets the whole YADE scene back, for reading
    if mp.rank == 0:
        try:
            O.run(1, True)  # refused: QDEM steps only inside mp.mpirun, on every rank
        except RuntimeError as e:
            out["mergedStep"] = str(e)
if qdem.mpi.isWriter():
    if os.environ.get("QDEM_MPI_OUT"):
        with open(os.environ["QDEM_MPI_OUT"], "w") as f:
            json.dump(out, f)
    else:
        print("RESULT " + json.dumps(out), flush=True)
