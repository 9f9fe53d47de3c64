"""YADE spheres and a clump against QDEM pieces, the same script serially and
under `mpiexec -n P yade -n -x tests/mpi/yade_spheres.py SCENE` (test_mpi.py):
every rank holds the whole YADE scene, the QDEM nodes are split.

SCENE: 'drop' (twelve spheres falling on a block that rests on a floor) or
'clump' (a three-sphere clump thrown along a slab on a floor).
Environment: QDEM_THREADS (QDEM's threads, for the serial 1-vs-2-thread
licence), QDEM_MPI_REBALANCE=1 (a forced rebalance mid-contact),
QDEM_MPI_SAVE=path (O.save mid-run, go on, O.load, go on again: both ends
compared).  Rank 0 writes the results as JSON to $QDEM_MPI_OUT (else prints
'RESULT {json}')."""
import json
import os
import sys

import numpy as np
from yade import O, utils
from yade.wrapper import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                          Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

import qdem

SCENE = sys.argv[1] if len(sys.argv) > 1 else "drop"
STEPS, CHUNK = int(os.environ.get("QDEM_MPI_STEPS", 1000)), 25
THREADS = int(os.environ.get("QDEM_THREADS", "1"))
REBALANCE = os.environ.get("QDEM_MPI_REBALANCE") == "1"
SAVE = os.environ.get("QDEM_MPI_SAVE")
G = np.array([0, 0, -9.81])
AT = 4 * STEPS // 5  # the step of the forced rebalance and of O.save: spheres resting on the block


def engines():
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                            [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
            qdem.QdemEngine(label="qe", threads=THREADS), NewtonIntegrator(gravity=tuple(G), damping=0.0)]


def build():
    O.bodies.append(utils.wall(0, axis=2, sense=1))  # body 0: the floor
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
    if SCENE == "drop":
        mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.004,
                           restitution=0.1, frictionPiece=0.5)
        piece = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.045))
        spheres = []
        for i in range(12):  # over the whole block: the split cuts under some of them
            x, y = -0.085 + 0.0155 * i, 0.03 * ((i % 3) - 1)
            b = O.bodies.append(utils.sphere((x, y, 0.098 + 0.003 * (i % 4)), 0.007, material=fm))
            O.bodies[b].state.vel = (0.05 * ((i % 2) * 2 - 1), 0, -0.3)
            spheres.append(b)
        return piece, spheres, []
    mat = qdem.QdemMat(young=5e6, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.003,
                       restitution=0.1, frictionPiece=0.6)
    piece = qdem.addPiece(qdem.boxMesh((0.3, 0.12, 0.03), (12, 5, 2)), mat, pos=(0, 0, 0.018))
    top = 0.033 + 0.003
    parts = [utils.sphere((0.0 + dx, dz * 0.5, top + 0.0099 + dz), r, material=fm)
             for dx, dz, r in ((0.0, 0.0, 0.01), (0.014, 0.004, 0.008), (-0.012, 0.006, 0.007))]
    clumpId, members = O.bodies.appendClumped(parts)
    O.bodies[clumpId].state.vel = (1.5, 0.0, 0.0)
    O.bodies[clumpId].state.angVel = (0.0, 0.0, 2.0)
    return piece, list(members), [clumpId]


O.trackEnergy = True
piece, spheres, clumps = build()
O.engines = engines()
O.dt = 0.5 * qe.stableTimeStep()  # noqa: F821 - YADE's label
core = qe.world.core  # noqa: F821
movers = clumps + [s for s in spheres if not O.bodies[s].isClumpMember]


def momentum():
    p = piece.momentum
    for b in movers:
        p = p + O.bodies[b].state.mass * np.array(O.bodies[b].state.vel)
    return p


def totalMass():
    return piece.totalMass + sum(O.bodies[b].state.mass for b in movers)


def sphereStates():
    return [list(O.bodies[b].state.pos) + list(O.bodies[b].state.vel) + list(O.bodies[b].state.angVel)
            for b in movers]


series, impulse, mine = [], np.zeros(3), 0
x0 = np.array(core.pos, copy=True)
p0, t0 = momentum(), O.time
for step in range(STEPS):
    O.step()
    impulse -= np.array(O.forces.f(0)) * O.dt  # the floor's push on the system
    mine += core.contactCounts["sphere"]  # computed on this rank
    if REBALANCE and step == AT and core.mpiSize > 1:
        before = np.array(core.nodeOwner)
        core.rebalance()  # forced, mid-contact: the split moves
        moved = int((np.array(core.nodeOwner) != before).sum())
    if SAVE and step == AT:
        O.save(SAVE)
    if (step + 1) % CHUNK == 0:
        n = qdem.mpi.summedCounts(core)["sphere"]
        series.append([n] + list(O.forces.f(0)) + [core.energy["total"]])
ledger = momentum() - p0 - impulse - totalMass() * G * (O.time - t0)
out = {"ranks": core.mpiSize, "threads": THREADS, "series": series, "pos": np.array(core.pos).tolist(),
       "spheres": sphereStates(), "momentumScale": float(totalMass() * 9.81 * (O.time - t0)),
       "ledger": ledger.tolist(), "iter": core.iter, "disp": float(np.abs(np.array(core.pos) - x0).max())}
# The sphere-piece contact histories (slot keys and tangential springs), as
# a restart keeps them: gathered first under MPI (collective).
if core.mpiSize > 1:
    core.gatherState()
state = core.saveState()
keys = np.frombuffer(state["sphereSlotKey"], dtype=np.int32)
shear = np.frombuffer(state["sphereSlotShear"], dtype=np.float64)
out["historyKeys"], out["historyShear"] = keys.tolist(), shear.tolist()
if core.mpiSize > 1:
    from mpi4py import MPI
    every = MPI.COMM_WORLD.allgather((keys.tobytes(), shear.tobytes()))
    out["historySameOnRanks"] = all(e == every[0] for e in every)
    every = MPI.COMM_WORLD.allgather(sphereStates())
    out["sphereRankSpread"] = float(max(np.abs(np.array(e) - np.array(every[0])).max() for e in every))
    out["rebalances"] = MPI.COMM_WORLD.allgather(core.partitionStats["rebalances"])
    out["sphereContactsPerRank"] = MPI.COMM_WORLD.allgather(mine)
    owner, x = np.array(core.nodeOwner), np.array(core.pos)
    out["ownedBoxes"] = [np.concatenate([x[owner == r].min(axis=0), x[owner == r].max(axis=0)]).round(4).tolist()
                         for r in range(core.mpiSize)]  # where the split cuts the pieces
    if REBALANCE:
        out["movedNodes"] = moved
if SAVE:
    cont = (np.array(core.pos), sphereStates(), core.iter)
    if core.mpiSize > 1:
        MPI.COMM_WORLD.Barrier()  # the file is written
    O.load(SAVE)
    core = qdem.defaultWorld().core
    for k in range(STEPS - AT - 1):
        O.step()
    out["reloaded"] = {"iter": [cont[2], core.iter], "dx": float(np.abs(np.array(core.pos) - cont[0]).max()),
                       "dSphere": float(np.abs(np.array(sphereStates()) - np.array(cont[1])).max())}
if qdem.mpi.isWriter():
    if os.environ.get("QDEM_MPI_OUT"):  # a long line: other ranks' exit messages would cut into it
        with open(os.environ["QDEM_MPI_OUT"], "w") as f:
            json.dump(out, f)
    else:
        print("RESULT " + json.dumps(out), flush=True)
