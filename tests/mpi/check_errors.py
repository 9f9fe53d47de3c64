"""Run by tests/python/test_mpi.py under mpiexec -n P: an error raised on one
rank stops every rank with its message (never a deadlock).  Rank 0 prints
'RESULT {json}' with what each rank caught."""
import json
import os
import sys

import numpy as np
from mpi4py import MPI

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qdem  # noqa: E402
import scenes  # noqa: E402

comm = MPI.COMM_WORLD


def caught(f):
    try:
        f()
    except Exception as e:  # noqa: BLE001 - the test reports the type
        return type(e).__name__, str(e)
    return None, ""


# (a) A piece that starts 3 cm through the floor: refused by the rank(s)
# owning its bottom; every rank raises the same error at the same step.
w = scenes.contactFree()
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, radius=0.004)
w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.6, 0.6, 0.0))
w.core.setCommunicator(comm)
dt = 0.5 * w.stableDt()["combined"]
a = caught(lambda: w.core.step(dt, 5))

# (b) A NaN velocity on one node of the last rank only: the integration of
# the rank that moves it finds it in that very step, and every rank stops
# with the same error at the step's end (World::step, Domain::finishStep).
w = scenes.contactFree()
w.core.setCommunicator(comm)
w.core.step(dt, 3)
owner = np.array(w.core.nodeOwner)
node = int(np.nonzero(owner == comm.size - 1)[0][0])
if comm.rank == comm.size - 1:
    w.core.vel[node, 0] = float("nan")


def stepAndCheck():
    w.core.step(dt, 2)
    w.core.gatherAll()
    w.core.checkFinite()


b = caught(stepAndCheck)

# (d) Ranks that built different scenes (unseeded random placement) are
# told so on every rank, before any message is cut short.
w = scenes.contactFree()
w.pieces[1].pos[:] += 1e-3 * comm.rank
w.core.setCommunicator(comm)
d = caught(lambda: w.core.step(dt, 1))
# (c) Ranks whose YADE copies hold other spheres (here: one sphere elsewhere
# on the last rank, as an unseeded random placement would do): refused on
# every rank at the step's start, before a reduction they would size apart.
w = scenes.withContacts()
w.core.setCommunicator(comm)
i32, f64 = np.int32, np.float64
w.core.setSpheres(np.array([7], i32), np.array([0.01]), np.array([1e7]), np.array([0.3]), np.array([0.5]),
                  np.array([-1.0]), np.array([0.01]), np.array([0, 1], i32), np.array([0], i32))
x = 0.05 if comm.rank == comm.size - 1 else 0.0
w.core.setSphereStates(np.array([[x, 0.0, 0.06]], f64), np.zeros((1, 3)), np.zeros((1, 3)))
c = caught(lambda: w.core.step(dt, 2))
# (e) Ranks whose scenes differ in something other than positions: node
# velocities drawn unseeded, a load set on one rank, another O.dt, a setting
# or a material changed on one rank.  Each ran on silently before, every rank
# integrating its own nodes by its own values (a block torn in two).
other = comm.rank == comm.size - 1
e = {}
w = scenes.contactFree()
w.pieces[1].vel[:] += 0.01 * comm.rank
w.core.setCommunicator(comm)
e["velocities"] = caught(lambda: w.core.step(dt, 1))
w = scenes.contactFree()
if other:
    w.pieces[0].extForce[0] = (0.0, 0.0, 1.0)
w.core.setCommunicator(comm)
e["loads"] = caught(lambda: w.core.step(dt, 1))
w = scenes.contactFree()
w.core.setCommunicator(comm)
e["time steps"] = caught(lambda: w.core.step(dt * (0.5 if other else 1.0), 1))
w = scenes.contactFree()
w.core.setCommunicator(comm)
w.core.step(dt, 1)
if other:
    w.core.localDamping = 0.1
e["settings"] = caught(lambda: w.core.step(dt, 1))
w = scenes.contactFree()
w.core.setCommunicator(comm)
if other:
    w.core.gravity = (0.0, 0.0, -9.0)
e["gravity"] = caught(lambda: w.core.step(dt, 1))
# (f) Two soft cubes thrown at each other faster than their contact can
# hold within its reach: the rank whose node goes deeper than the reach
# stops, and every rank raises the same error in that step
# (ContactDepthCheck.cpp, Domain::finishStep).
w = qdem.World()
soft = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=20, radius=0.005, restitution=0.5)
cube = qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4))
w.addPiece(cube, soft, pos=(-0.15, 0, 0), vel=(10.0, 0, 0))
w.addPiece(cube, soft, pos=(0.15, 0.03, 0), vel=(-10.0, 0, 0))
w.core.setCommunicator(comm)
fdt = 0.8 * w.stableDt()["combined"]
f = caught(lambda: w.core.step(fdt, 200))
fIter = int(w.core.iter)
everything = comm.gather({"rank": comm.rank, "a": a, "b": b, "c": c, "d": d, "e": e, "f": f, "fIter": fIter},
                         root=0)
if comm.rank == 0:
    print("RESULT " + json.dumps({"ranks": comm.size, "caught": everything, "nanNode": node}), flush=True)
