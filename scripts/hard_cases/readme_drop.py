"""The README's drop (issue 12): a 0.4 m soft cube, 8x8x8 cells of 6 tets,
dropped flat from 0.6 m on a YADE wall, 10,000 steps at 0.8 of the stable
step.  Prints the centroid, the largest |angular momentum| after the first
landing, the floor force and the inverted tetrahedra.
Run: PYTHONPATH=build/python yade -n -x scripts/hard_cases/readme_drop.py [tetsPerCell] [steps]"""
import sys

import numpy as np

import qdem
from yade import O, ForceResetter, NewtonIntegrator, utils

k = int(sys.argv[1]) if len(sys.argv) > 1 else 6
steps = int(sys.argv[2]) if len(sys.argv) > 2 else 10000
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=20, radius=0.01)
block = qdem.addPiece(qdem.boxMesh((0.4, 0.4, 0.4), (8, 8, 8), tetsPerCell=k), mat, pos=(0, 0, 0.6))
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.8 * qe.stableDt()["combined"]
touched, Lmax, firstLeft = False, 0.0, None
for i in range(steps // 50):
    O.run(50, True)
    fz = O.forces.f(floor)[2]
    if fz < 0:
        touched = True
    elif touched and firstLeft is None:
        firstLeft = O.iter
    if touched and firstLeft is None:
        Lmax = max(Lmax, np.linalg.norm(block.angularMomentum))
    if firstLeft is not None and O.iter < firstLeft + 200:
        Lmax = max(Lmax, np.linalg.norm(block.angularMomentum))
tets = block.tets
x = block.pos
d = np.einsum("ij,ij->i", np.cross(x[tets[:, 1]] - x[tets[:, 0]], x[tets[:, 2]] - x[tets[:, 0]]), x[tets[:, 3]] - x[tets[:, 0]])
print("tetsPerCell %d: centroid %s, |L| max around the first landing %.3g kg m^2/s, floor force %s, inverted %d"
      % (k, np.round(block.centroid, 4), Lmax, np.round(O.forces.f(floor), 1), int((d <= 0).sum())))
