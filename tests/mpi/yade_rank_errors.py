"""Errors on some ranks of a YADE script under mpiexec must end the job with
the message, never leave the other ranks waiting (tests/python/test_mpi.py).
argv: CASE [DIR]
  typo     an AttributeError inside `if rank == 0:` between two O.run calls
  save     O.save into a directory that does not exist (rank 0 writes)
  savecaught  the same, caught by the script on every rank: the run goes on
  steps    rank 0 runs fewer steps than the others, then ends
  save0    O.save inside `if rank == 0:` (a collective on one rank)
  state0   qdem.saveState inside `if rank == 0:`
"""
import os
import sys

import qdem
from yade import O, utils
from yade.wrapper import ForceResetter, NewtonIntegrator

case = sys.argv[1]
rank = qdem.mpi.rank()
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=5, radius=0.004)
piece = qdem.addPiece(qdem.boxMesh((0.2, 0.1, 0.05), (8, 4, 2)), mat, pos=(0, 0, 0.1))
O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.5 * qe.stableTimeStep()  # noqa: F821 (label)
O.run(20, True)
missing = os.path.join(sys.argv[2] if len(sys.argv) > 2 else "/tmp", "no_such_dir", "scene.yade.gz")
if case == "typo":
    if rank == 0:
        print(piece.no_such_attribute)
elif case == "save":
    O.save(missing)
elif case == "savecaught":
    try:
        O.save(missing)
    except (OSError, RuntimeError) as e:
        print("RANK %d CAUGHT %s" % (rank, type(e).__name__), flush=True)
elif case in ("save0", "state0"):
    if rank == 0:
        O.save(os.path.join(sys.argv[2], "s.yade")) if case == "save0" else qdem.saveState(
            os.path.join(sys.argv[2], "s.npz"))
O.run(10 if case == "steps" and rank == 0 else 20, True)
print("RANK %d FINISHED iter %d" % (rank, O.iter), flush=True)
