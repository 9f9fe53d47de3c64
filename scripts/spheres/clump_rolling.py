# A YADE clump rolls over a deformable QDEM slab (issue 5 example).
#
#   yade -j 2 -n -x scripts/spheres/clump_rolling.py
#
# A clump of three spheres (an uneven "pebble") is launched along a soft slab
# resting on the floor, without spin.  Friction at the sphere-slab contacts
# spins it up through the members' torques (NewtonIntegrator sums the members'
# forces and torques into the clump, as for any YADE clump) until it rolls.
# The slab dents under it as it passes.
#
# Parameters: friction (tan of the clump's friction angle), speed [m/s],
# duration [s].  Writes out/spheres/clump/: slab VTU series (slab.pvd),
# rolling.json (clump speed, spin, slip velocity at the lowest point, energy
# terms) and rolling.png.
import json
import math
import os

import numpy as np
import qdem
from yade import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                  Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                  Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, O, PyRunner, utils)
from yade.utils import readParamsFromTable

readParamsFromTable(friction=0.4, speed=0.8, duration=0.6, noTableOk=True)
from yade.params import table as P  # noqa: E402

out = "out/spheres/clump"
os.makedirs(out, exist_ok=True)

mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=5.0, radius=0.002, frictionPiece=1.0,
                   frictionWall=0.8)
T = 0.03
slab = qdem.addPiece(qdem.boxMesh((0.8, 0.12, T), (40, 6, 3)), mat, pos=(0.25, 0, T / 2 + mat.radius))
O.bodies.append(utils.wall(0, axis=2, sense=1))

cm = O.materials.append(FrictMat(young=2e7, poisson=0.3, frictionAngle=math.atan(P.friction), density=2500))
z = T + 2 * mat.radius
R = 0.015
clump, members = O.bodies.appendClumped([
    utils.sphere((-0.1, 0.0, z + R), R, material=cm),
    utils.sphere((-0.1 + 0.012, 0.004, z + R + 0.006), 0.011, material=cm),
    utils.sphere((-0.1 - 0.006, -0.008, z + R + 0.004), 0.012, material=cm)])
O.bodies[clump].state.vel = (P.speed, 0, 0)

engine = qdem.QdemEngine(progressPeriod=5000)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
             engine, PyRunner(command="sample()", iterPeriod=100),
             qdem.VtkRecorder(fileBase=out + "/slab-", iterPeriod=2000),
             NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
O.dt = min(0.5 * utils.PWaveTimeStep(), 0.8 * engine.stableDt()["combined"])
O.trackEnergy = True
top = np.isclose(slab.refPos[:, 2], slab.refPos[:, 2].max())
rec = {"t": [], "x": [], "vx": [], "spin": [], "slip": [], "contacts": [], "dent": []}


def sample():
    s = O.bodies[clump].state
    # Slip velocity of the clump's lowest member point against the slab.
    low = min(members, key=lambda i: O.bodies[i].state.pos[2] - O.bodies[i].shape.radius)
    b = O.bodies[low]
    r = np.array([0, 0, -b.shape.radius])
    vPoint = np.array(s.vel) + np.cross(np.array(s.angVel), np.array(b.state.pos) - np.array(s.pos) + r)
    rec["t"].append(O.time)
    rec["x"].append(s.pos[0])
    rec["vx"].append(s.vel[0])
    rec["spin"].append(s.angVel[1])
    rec["slip"].append(vPoint[0])
    rec["contacts"].append(int(engine.world.core.contactCounts["sphere"]))
    rec["dent"].append(float((slab.refPos[top, 2] - slab.pos[top, 2]).max()))  # deepest point of the top face

O.run(int(P.duration / O.dt), True)
res = {"friction": P.friction, "speed": P.speed, "final_vx": rec["vx"][-1], "final_slip": rec["slip"][-1],
       "energy": {k: float(v) for k, v in O.energy.items()}, "series": rec}
with open(out + "/rolling.json", "w") as f:
    json.dump(res, f)

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, ax = plt.subplots(1, 2, figsize=(10, 3.5))
ax[0].plot(rec["t"], rec["vx"], label="clump speed")
ax[0].plot(rec["t"], rec["slip"], label="slip at the lowest point")
ax[0].set(xlabel="t [s]", ylabel="m/s", title="sliding turns into rolling")
ax[0].legend()
ax[1].plot(rec["t"], rec["spin"])
ax[1].set(xlabel="t [s]", ylabel="rad/s", title="clump spin about y")
fig.tight_layout()
fig.savefig(out + "/rolling.png", dpi=100)
print("clump_rolling: final speed %.3f m/s, slip %.3g m/s -> %s" % (rec["vx"][-1], rec["slip"][-1], out))
