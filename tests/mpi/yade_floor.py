"""A QDEM block resting on a YADE floor: the same script serially and under
`mpiexec -n P yade -n -x tests/mpi/yade_floor.py` (test_mpi.py).  Rank 0
prints 'RESULT {json}' with the floor force and the block's weight."""
import json

from yade import O, utils
from yade.wrapper import ForceResetter, NewtonIntegrator

import qdem

O.bodies.append(utils.wall(0, axis=2, sense=1))
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5)
block = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.045))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", damping=0.3), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.5 * qdem.stableDt()["combined"]
O.run(2000, True)
core = qe.world.core  # noqa: F821 - YADE's label
if qdem.mpi.isWriter():
    print("RESULT " + json.dumps({"ranks": core.mpiSize, "floor": list(O.forces.f(0)), "weight": block.totalMass * 9.81,
                                  "zmin": float(block.pos[:, 2].min()), "iter": core.iter,
                                  "energy": core.energy["total"]}), flush=True)
