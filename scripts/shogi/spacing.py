# Does a line of three rooks propagate?  Centre-of-mass height of each piece
# (relative to standing) over 0.3 s, for a spacing and a push given on the
# command line (in tallest heights and in sqrt(g/H)); 0.34 = lying flat.
#
#   yade -n -x scripts/shogi/spacing.py 0.5 1.5     (comes to rest leaning)
#   yade -n -x scripts/shogi/spacing.py 0.8 1.0     (propagates)
import math
import sys

import qdem
from qdem.scenes import shogi
from yade import O, ForceResetter, NewtonIntegrator, utils

spacing, push = float(sys.argv[1]), float(sys.argv[2])
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=700, viscosity=0.3, radius=5e-4, frictionPiece=0.1,
                   frictionWall=0.5)
H = shogi.KINDS["rook"][0] * 1e-3
pieces = shogi.dominoLine(["rook"] * 3, mat, spacing=spacing, push=push * math.sqrt(9.81 / H))
O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.8 * O.engines[1].stableDt()["combined"]
z0 = [p.centroid[2] for p in pieces]
for _ in range(6):
    O.run(int(0.05 / O.dt), True)
    print("spacing %.2f push %.2f  t=%.2f s  relative heights %s"
          % (spacing, push, O.time, " ".join("%.2f" % (p.centroid[2] / z) for p, z in zip(pieces, z0))))
