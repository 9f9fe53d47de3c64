"""YADE alone (no QDEM) under yade.mpy: a three-sphere clump on a worker falls
onto a floor that mpy keeps on its master.  The evidence behind doc/parallel.md,
"Under yade.mpy", what is left (sphere-wall contacts are mpy's business).

    yade -n -x scripts/mpi/mpy_clump_floor.py                    # serial: the clump bounces
    mpiexec --allow-run-as-root --oversubscribe -n 3 yade -n -x scripts/mpi/mpy_clump_floor.py

Prints the clump's height and vertical velocity after 2,000 steps (0.04 s):
serially it has bounced (z near 0.012 m, vz > 0); under mpy it fell through
the floor (z = 0.0045 m, vz = -0.39 m/s: free fall)."""
from yade import O, mpy as mp, utils
from yade.wrapper import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                          Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

O.bodies.append(utils.wall(0, axis=2, sense=1))
fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
parts = [utils.sphere((dx, dz * 0.5, 0.0101 + dz), r, material=fm)
         for dx, dz, r in ((0.0, 0.0, 0.01), (0.014, 0.004, 0.008), (-0.012, 0.006, 0.007))]
cid, members = O.bodies.appendClumped(parts)
O.bodies[cid].state.vel = (1.5, 0.0, 0.0)
if mp.numThreads and mp.numThreads > 1:
    for i in [cid] + list(members):
        O.bodies[i].subdomain = 1  # the clump on worker 1; the floor stays on the master
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
             NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
O.dt = 2e-5
mp.mpirun(2000)
b = O.bodies[cid] if cid < len(O.bodies) else None
if b is not None and (not mp.numThreads or mp.numThreads == 1 or b.subdomain == mp.rank):
    print("clump after %d steps: z = %.5f m, vz = %.4f m/s" % (O.iter, b.state.pos[2], b.state.vel[2]), flush=True)
