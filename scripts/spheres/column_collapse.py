# A granular column collapses onto a deformable QDEM block (issue 5 example).
#
#   yade -j 2 -n -x scripts/spheres/column_collapse.py
#   yade-batch -j 1 --job-threads 2 scripts/spheres/friction.table scripts/spheres/column_collapse.py
#
# A column of YADE spheres is poured behind a gate (a YADE Box), the gate is
# erased and the column collapses sideways onto a soft QDEM block standing on
# the floor.  YADE handles the spheres (InsertionSortCollider, InteractionLoop,
# NewtonIntegrator); QdemEngine steps the block and couples it to the spheres.
#
# Parameters (yade-batch columns, or the defaults):
#   sphereFriction  tan of the spheres' friction angle
#   blockYoung      Young's modulus of the block [Pa]
#   settle          seconds of pouring behind the gate
#   duration        seconds of collapse after the gate is gone
# Writes out/spheres/column_mu<f>/: block VTU series (block.pvd), spheres VTU
# series (YADE's VTKRecorder), collapse.json (runout, block load and
# compression against time) and collapse.png.
import json
import math
import os
import time

import numpy as np
import qdem
from yade import (Bo1_Box_Aabb, Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Box_Sphere_ScGeom,
                  Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                  Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, O,
                  PyRunner, pack, utils)
from yade.utils import readParamsFromTable

readParamsFromTable(sphereFriction=0.5, blockYoung=3e5, settle=0.25, duration=0.6, noTableOk=True)
from yade.params import table as P  # noqa: E402

out = "out/spheres/column_mu%g" % P.sphereFriction
os.makedirs(out, exist_ok=True)

# The block: 12 cm long, across the whole 20 cm channel (less a 5 mm gap to
# each side wall), 8 cm high, soft, its face 4 cm in front of the column.
B, W, Hb = 0.12, 0.19, 0.08
mat = qdem.QdemMat(young=P.blockYoung, poisson=0.3, density=1000.0, viscosity=30.0, radius=0.002,
                   frictionPiece=1.0, frictionWall=0.5)
block = qdem.addPiece(qdem.boxMesh((B, W, Hb), (8, 12, 5)), mat, pos=(0.10, 0, Hb / 2 + mat.radius))

# Floor, side walls (y) and the gate that holds the column at x = 0.
wm = O.materials.append(FrictMat(young=1e7, frictionAngle=math.atan(0.5), density=1000))
O.bodies.append(utils.wall(0, axis=2, sense=1, material=wm))
O.bodies.append(utils.wall(-0.1, axis=1, sense=1, material=wm))
O.bodies.append(utils.wall(0.1, axis=1, sense=-1, material=wm))
O.bodies.append(utils.wall(-0.1, axis=0, sense=1, material=wm))
gate = O.bodies.append(utils.box((0.005, 0, 0.25), (0.005, 0.1, 0.25), fixed=True, material=wm))

sm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=math.atan(P.sphereFriction),
                                 density=2500))
sp = pack.SpherePack()
sp.makeCloud((-0.099, -0.099, 0.001), (-0.001, 0.099, 0.3), rMean=0.004, rRelFuzz=0.2, seed=11)
ids = sp.toSimulation(material=sm)

engine = qdem.QdemEngine(progressPeriod=2000)
O.engines = [ForceResetter(),
             InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb(), Bo1_Box_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom(), Ig2_Box_Sphere_ScGeom()],
                             [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
             engine,
             PyRunner(command="sample()", iterPeriod=200),
             qdem.VtkRecorder(fileBase=out + "/block-", iterPeriod=2000),
             NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.2)]
try:
    from yade import VTKRecorder
    O.engines = O.engines[:-1] + [VTKRecorder(fileName=out + "/spheres-", recorders=["spheres", "velocity"],
                                              iterPeriod=2000)] + O.engines[-1:]
except ImportError:
    print("column_collapse: this YADE has no VTKRecorder; block VTU only")
O.dt = min(0.5 * utils.PWaveTimeStep(), 0.8 * engine.stableDt()["combined"])

top = np.isclose(block.refPos[:, 2], block.refPos[:, 2].max())
bot = np.isclose(block.refPos[:, 2], block.refPos[:, 2].min())
h0 = block.refPos[top, 2].mean() - block.refPos[bot, 2].mean()
series = {"t": [], "runout": [], "load": [], "compression": [], "contacts": []}


def sample():
    x = max(O.bodies[i].state.pos[0] + O.bodies[i].shape.radius for i in ids)
    series["t"].append(O.time)
    series["runout"].append(x)
    series["load"].append(float(np.abs(engine.world.core.sphereForceTorque()[:, :3]).sum()))
    series["compression"].append(float(h0 - (block.pos[top, 2].mean() - block.pos[bot, 2].mean())))
    series["contacts"].append(int(engine.world.core.contactCounts["sphere"]))


print("column_collapse: %d spheres, block %d tets, dt %.3g s, friction %g" % (len(ids), block.tets.shape[0], O.dt,
                                                                              P.sphereFriction))
start = time.time()
O.timingEnabled = True  # per-engine cost, printed at the end
engine.damping = 0.5  # while the column is poured the block settles quasi-statically
O.run(int(P.settle / O.dt), True)
engine.damping = 0.0  # then the dynamics are exact
O.bodies.erase(gate)
tGate = O.time
h0 = block.pos[top, 2].mean() - block.pos[bot, 2].mean()  # settled under its own weight: the reference
O.run(int(P.duration / O.dt), True)
wall = time.time() - start

res = {"spheres": len(ids), "sphereFriction": P.sphereFriction, "blockYoung": P.blockYoung, "gate_time": tGate,
       "final_runout": series["runout"][-1], "max_block_load": max(series["load"]),
       "max_compression": max(c for t, c in zip(series["t"], series["compression"]) if t >= tGate),
       "wall_s": wall, "series": series}
with open(out + "/collapse.json", "w") as f:
    json.dump(res, f)

import matplotlib  # noqa: E402
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

t = np.array(series["t"]) - tGate
fig, ax = plt.subplots(1, 3, figsize=(12, 3.5))
ax[0].plot(t, series["runout"])
ax[0].axvline(0, ls=":", c="k")
ax[0].axhline(0.10 - B / 2, ls="--", c="gray", label="block face")
ax[0].set(xlabel="t after gate [s]", ylabel="front x [m]", title="runout")
ax[0].legend()
ax[1].plot(t, series["load"])
ax[1].set(xlabel="t after gate [s]", ylabel="|F| sum [N]", title="spheres on the block")
after = t >= 0
ax[2].plot(t[after], 1e3 * np.array(series["compression"])[after])
ax[2].set(xlabel="t after gate [s]", ylabel="mm (own weight excluded)", title="block shortening")
fig.suptitle("granular column onto a QDEM block, sphere friction %g" % P.sphereFriction)
fig.tight_layout()
fig.savefig(out + "/collapse.png", dpi=100)
for e in O.engines:
    print("column_collapse: %-22s %7.3f ms/step" % (type(e).__name__, e.execTime * 1e-6 / max(O.iter, 1)))
print("column_collapse: runout %.3f m, peak load %.3g N, peak compression %.3g mm, wall %.0f s -> %s"
      % (res["final_runout"], res["max_block_load"], 1e3 * res["max_compression"], wall, out))
