"""A stiff cube dropped flat on a floor at 1 m/s: the rebound ratio of the
whole piece against QdemMat.restitution, on 2^3 and 4^3 cells
(doc/hard_cases.md, "Known limits": restitution is that of one node contact).

Run: PYTHONPATH=build/python yade -n -x scripts/hard_cases/rebound_vs_restitution.py
"""
import qdem
from yade import O, ForceResetter, NewtonIntegrator, utils

print("restitution  cells  rebound/impact")
for e in (0.2, 0.5, 0.8):
    for n in (2, 4):
        O.reset()
        mat = qdem.QdemMat(young=1e8, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.005,
                           restitution=e, frictionWall=0.0)
        block = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (n, n, n)), mat, pos=(0, 0, 0.0551), vel=(0, 0, -1))
        O.bodies.append(utils.wall(0, axis=2, sense=1))
        O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, 0))]
        O.dt = 0.5 * qe.stableTimeStep()
        O.run(int(0.01 / O.dt), True)
        print("%11.1f  %5d  %14.3f" % (e, n, block.velocity[2]))
