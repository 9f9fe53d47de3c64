# Default demo: a deformable viscoelastic block dropped onto a YADE floor.
# It bounces, rocks and comes to rest; VTU frames (ParaView: open
# out/demo/block.pvd) and a PNG energy plot are written under out/demo/.
#
#   yade -n -x scripts/demo.py [simulated seconds]
import os
import sys
import time

import qdem
from yade import O, ForceResetter, NewtonIntegrator, PyRunner, utils

OUT = "out/demo"
os.makedirs(OUT, exist_ok=True)
duration = float(sys.argv[1]) if len(sys.argv) > 1 else 4.0

# A soft rubber-like block (E = 2 MPa, first-mode damping ratio ~0.1), 0.4 m
# wide, tilted so that it lands on an edge, tips and settles on a face.
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=700, frictionWall=0.5, radius=0.01,
                   restitution=0.2)
block = qdem.addPiece(qdem.boxMesh((0.4, 0.4, 0.4), (8, 8, 8), tetsPerCell=6), mat, pos=(0, 0, 0.6),
                      ori=((1, 1, 0), 0.4))
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))

history = {"t": [], "kinetic": [], "elastic": [], "gravity": [], "dissipated": []}


def sample():
    e = O.energy
    history["t"].append(O.time)
    history["kinetic"].append(e["qdemKinetic"])
    history["elastic"].append(e["qdemElastic"] + e["qdemContactElastic"])
    history["gravity"].append(e["qdemGravWork"])
    history["dissipated"].append(e["qdemViscDissip"] + e["qdemContactDamp"] + e["qdemFrictDissip"])


O.engines = [
    ForceResetter(),
    qdem.QdemEngine(label="qdemEngine", progressPeriod=20000),
    qdem.VtkRecorder(fileBase=OUT + "/block-", iterPeriod=2000),
    PyRunner(command="sample()", iterPeriod=400),
    NewtonIntegrator(gravity=(0, 0, -9.81)),
]
O.trackEnergy = True
limits = qdemEngine.stableDt()
O.dt = 0.8 * limits["combined"]
print("demo: %d nodes, %d tets; stable dt %.3g s (limited by %s), O.dt = %.3g s"
      % (block.pos.shape[0], len(block.tets), limits["combined"], limits["limitedBy"], O.dt))

start = time.time()
O.run(int(duration / O.dt), True)
wall = time.time() - start

from qdem.io.plot import energyPlot  # noqa: E402

energyPlot(OUT + "/energy.png", history["t"], {k: v for k, v in history.items() if k != "t"},
           title="Block dropped on a YADE floor")
from qdem import render  # noqa: E402

render.snapshot(qdem.defaultWorld(), OUT + "/block.png", title="t = %.2f s" % O.time, floor=0.0)
weight = block.totalMass * 9.81
load = -O.forces.f(floor)[2]  # what the block pushes on the floor: YADE's reaction on the wall, reversed
c = qdemEngine.world.core.contactCounts
print("demo: %.2f s simulated in %.1f s wall (%d steps, %.0f steps/s)" % (O.time, wall, O.iter, O.iter / wall))
print("demo: the floor carries %.4g N, the block weighs %.4g N (ratio %.4f), through %d node-wall contacts; "
      "centre at z = %.4f m; %d elements inverted at most"
      % (load, weight, load / weight, c["wall"], block.centroid[2], qdemEngine.inverted["max"]))
print("demo: wrote %s/block-*.vtu (%d frames, block.pvd for ParaView), %s/energy.png and %s/block.png"
      % (OUT, len(O.engines[2].frames), OUT, OUT))
