"""O.save / O.load under `mpiexec -n P yade -n -x tests/mpi/yade_save_load.py`
(test_mpi.py): a QDEM block on a floor, saved mid-run (rank 0 writes), then
the run goes on; the saved scene is loaded on every rank and run as far:
both must end alike.  Rank 0 prints 'RESULT {json}'."""
import json
import os
import sys

from yade import O, utils
from yade.wrapper import ForceResetter, NewtonIntegrator

import qdem

path = sys.argv[1] if len(sys.argv) > 1 else "/tmp/qdem_mpi_scene.yade.gz"
O.bodies.append(utils.wall(0, axis=2, sense=1))
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5)
block = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.046), vel=(0.2, 0, 0))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.5 * qdem.stableDt()["combined"]
O.run(300, True)
O.save(path)
O.run(300, True)
cont = (qe.world.core.pos.copy(), list(O.forces.f(0)), qe.world.core.iter)  # noqa: F821
from mpi4py import MPI  # noqa: E402
MPI.COMM_WORLD.Barrier()  # the file is written
O.load(path)
O.run(300, True)
core = qdem.defaultWorld().core
if qdem.mpi.isWriter():
    print("RESULT " + json.dumps({"ranks": core.mpiSize, "iter": [cont[2], core.iter],
                                  "dx": float(abs(core.pos - cont[0]).max()),
                                  "floor": [cont[1][2], list(O.forces.f(0))[2]]}), flush=True)
    os.remove(path)
