"""What happens to a QDEM scene with YADE spheres under YADE's own MPI mode
(yade.mpy), with qdem's refusal of mpy bypassed: the evidence behind
doc/parallel.md, "YADE's MPI mode (mpy)".

    mpiexec --allow-run-as-root --oversubscribe -n 3 yade -n -x scripts/mpi/mpy_probe.py [MODE]

MODE 'refused' (default): qdem refuses mpy at the first step (the message).
MODE 'bypass': the refusal is bypassed; QDEM splits its own world over the
ranks (its communicator duplicated from mpy's) while mpy splits the YADE
bodies by Body.subdomain (spheres by x, the floor and the proxies on rank 0).
MODE 'replicated': bypassed, and QDEM does not split: every rank steps the
whole QDEM world (what happened before issue 14).
(In the bypass modes the engine gets a fixed id, so that the workers, whose
scene mpy replaces by the master's, find their own engine by it.)
Each rank prints what it sees."""
import sys

from yade import mpy as mp
from yade import O, utils
from yade.wrapper import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                          Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

import qdem

MODE = sys.argv[1] if len(sys.argv) > 1 else "refused"
NP = 3
if MODE != "refused":
    qdem.parallel._mpyInUse = lambda: False
if MODE == "replicated":
    qdem.parallel.launchedSize = lambda: 1

O.bodies.append(utils.wall(0, axis=2, sense=1))
fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.004, restitution=0.1)
block = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.045))
for i in range(12):
    x, y = -0.085 + 0.0155 * i, 0.03 * ((i % 3) - 1)
    b = O.bodies.append(utils.sphere((x, y, 0.098 + 0.003 * (i % 4)), 0.007, material=fm))
    O.bodies[b].subdomain = 1 + (i * (NP - 1)) // 12  # spheres to the workers, by x
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
             qdem.QdemEngine(label="qe", **({} if MODE == "refused" else {"qdemId": "mpy-probe"})), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
O.dt = 0.5 * qe.stableTimeStep()  # noqa: F821
try:
    mp.mpirun(400, NP)
    core = qdem.defaultWorld().core
    core.gatherAll()
    mp.mprint("after 400 steps: QDEM world split over %d rank(s), block zmin %.5f, floor force %s"
              % (core.mpiSize, float(block.pos[:, 2].min()), O.forces.f(0) if O.bodies[0] else None), force=True)
except Exception as e:
    text = str(e)  # on workers a PyRunner error wrapping qdem's: its message from 'qdem:' / 'QDEM' on
    at = min([i for i in (text.find("qdem:"), text.find("QDEM")) if i >= 0] or [0])
    mp.mprint("%s: %s" % (type(e).__name__, " ".join(text[at:at + 200].split())), force=True)
# What this rank's YADE holds after mpy's split, and what QDEM was given.
here = [b for b in O.bodies if b is not None]
kinds = {}
for b in here:
    k = "subdomain" if b.isSubdomain else type(b.shape).__name__
    kinds[k] = kinds.get(k, 0) + 1
core = qdem.defaultWorld().core
mp.mprint("holds %s (spheres of subdomains %s); the label qe is a %s; QDEM sees %d obstacle(s), %d sphere(s)"
          % (kinds, sorted({b.subdomain for b in here if type(b.shape).__name__ == "Sphere"}),
             type(qe).__name__, core.nObstacles, core.nSpheres), force=True)  # noqa: F821
