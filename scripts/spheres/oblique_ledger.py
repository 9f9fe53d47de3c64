# A YADE sphere thrown obliquely onto a held QDEM slab: friction work and the
# energy ledger (doc/spheres.md, "Energy").
#
#   yade -n -x scripts/spheres/oblique_ledger.py [dtFactor] [friction] [scale=S] [json=OUT.json]
#
# A sphere (R 1 cm, 2500 kg/m3) thrown at (1, 0.2, 0) m/s from 1 cm above a
# held soft slab (E 1 MPa, mu 0.5) bounces, slides and ends up rolling.
# Printed: the steps at which qdemFrictDissip fell (friction work booked
# negative: there must be none), the largest drift of the sum of O.energy
# from its start over the run, as a share of the kinetic energy thrown in,
# and the end state's rolling ratio |w| R / |v| (1 when rolling).
# dtFactor (default 0.5) is O.dt over QdemEngine.stableTimeStep() (also
# capped at 0.3 of YADE's PWaveTimeStep); friction 0 makes the contact
# frictionless. scale=S multiplies the step so chosen (0.5, 0.25: the
# ledger's order in dt); json=OUT.json adds this run's figures to OUT.json
# under "dt<dtFactor>_mu<friction>_x<scale>" (kept in bench/logs/ for
# doc/spheres.md).
import json
import math
import os
import sys

import qdem
from yade import (O, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                  InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack,
                  NewtonIntegrator, utils)

kwargs = dict(a.split("=", 1) for a in sys.argv[1:] if "=" in a)
args = [a for a in sys.argv[1:] if not a.startswith("-") and "=" not in a]
scale = float(kwargs.get("scale", 1.0))
dtFactor = float(args[0]) if args else 0.5
mu = float(args[1]) if len(args) > 1 else 0.5
mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=0.002, frictionPiece=mu)
T, R = 0.04, 0.01
slab = qdem.addPiece(qdem.boxMesh((0.4, 0.2, T), (8, 4, 2)), mat, pos=(0, 0, T / 2))
slab.dynamic = False  # held: only the sphere moves
fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=math.atan(mu), density=2500))
sid = O.bodies.append(utils.sphere((-0.1, 0.0, T + 0.002 + R + 0.01), R, material=fm))
O.bodies[sid].state.vel = (1.0, 0.2, 0)
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                             [Law2_ScGeom_FrictPhys_CundallStrack()]),
             qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
O.dt = scale * min(0.3 * utils.PWaveTimeStep(), dtFactor * qe.stableTimeStep())  # noqa: F821 (qe: YADE label)
O.trackEnergy = True
kin0 = 0.5 * O.bodies[sid].state.mass * (1.0 ** 2 + 0.2 ** 2)
last, falls, start, drift = 0.0, [], None, 0.0
for _ in range(int(0.25 / O.dt)):
    O.step()
    f = O.energy["qdemFrictDissip"] if "qdemFrictDissip" in O.energy.keys() else 0.0
    if f < last - 1e-15:
        falls.append((O.iter, f - last))
    last = f
    total = sum(v for _, v in O.energy.items())
    start = total if start is None else start
    drift = max(drift, abs(total - start))
s = O.bodies[sid].state
print("dt %.3e (%.2f of the stable step), friction %.2f" % (O.dt, dtFactor, mu))
print("friction work %.3e J, %d steps at which it fell" % (last, len(falls)))
print("largest ledger drift %.3e J = %.2f %% of the kinetic energy thrown in (%.3e J)"
      % (drift, 100 * drift / kin0, kin0))
print("end: |w| R / |v| = %.3f" % (s.angVel.norm() * R / math.hypot(s.vel[0], s.vel[1])))
if "json" in kwargs:
    runs = json.load(open(kwargs["json"])) if os.path.exists(kwargs["json"]) else {
        "source": "scripts/spheres/oblique_ledger.py", "runs": {}}
    runs["runs"]["dt%g_mu%g_x%g" % (dtFactor, mu, scale)] = {
        "dtFactor": dtFactor, "friction": mu, "scale": scale, "dt": O.dt,
        "dt_over_pwave": O.dt / utils.PWaveTimeStep(), "friction_work_J": last, "friction_falls": len(falls),
        "drift_J": drift, "kinetic_J": kin0, "drift_over_kinetic": drift / kin0,
        "rolling_ratio": s.angVel.norm() * R / math.hypot(s.vel[0], s.vel[1])}
    with open(kwargs["json"], "w") as f:
        json.dump(runs, f, indent=1)
