"""A 0.1 m SNH cube (6^3 cells, E = 1 MPa) squeezed between two walls moving
together at 5 cm/s, frictionless or with friction: wall force over the
analytic uniaxial-stress force, lateral stretch, inverted elements
(doc/hard_cases.md, "Known limits").

Run: PYTHONPATH=build/python yade -n -x scripts/hard_cases/squeeze_frictionless.py [frictionWall] [radius]
"""
import sys

import numpy as np
from scipy.optimize import brentq

import qdem
from yade import O, ForceResetter, NewtonIntegrator, utils

fw = float(sys.argv[1]) if len(sys.argv) > 1 else 0.0
r = float(sys.argv[2]) if len(sys.argv) > 2 else 0.008
E, nu, rho, a = 1e6, 0.3, 1000.0, 0.1
mat = qdem.QdemMat(young=E, poisson=nu, density=rho, viscosity=20.0, radius=r, frictionWall=fw)
p = qdem.addPiece(qdem.boxMesh((a, a, a), (6, 6, 6)), mat, pos=(0, 0, a / 2 + r))
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
top = O.bodies.append(utils.wall(a + 2 * r, axis=2, sense=-1))
O.bodies[top].state.vel = (0, 0, -0.05)
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, 0))]
O.dt = 0.5 * qe.stableTimeStep()
lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / 2 / (1 + nu)
mu_, la_ = 4 / 3 * mu, lam + 5 / 6 * mu          # stable neo-Hookean (doc/formulation.md 1.1)
alpha = 1 + 3 * mu_ / (4 * la_)


def firstPiola(l, s):
    F = np.diag([l, s, s])
    Ic, J = (F * F).sum(), l * s * s
    return mu_ * (1 - 1 / (Ic + 1)) * F + la_ * (J - alpha) * np.diag([s * s, l * s, l * s])


print("strain  wall force / analytic  lateral stretch qdem / analytic  inverted (max)")
X0 = np.array(p.refPos)
topN, botN = X0[:, 2] > X0[:, 2].max() - 1e-9, X0[:, 2] < X0[:, 2].min() + 1e-9
right, left = X0[:, 0] > X0[:, 0].max() - 1e-9, X0[:, 0] < X0[:, 0].min() + 1e-9
while True:
    try:
        O.run(int(0.1 / O.dt), True)
    except Exception as e:
        print("stopped:", str(e)[:300])
        break
    X = np.array(p.pos)
    l = (X[topN, 2].mean() - X[botN, 2].mean()) / a
    s = brentq(lambda s_: firstPiola(l, s_)[1, 1], 0.3, 3.0)
    width = (X[right, 0].mean() - X[left, 0].mean()) / a
    print("%.3f   %.3f   %.4f / %.4f   %d" % (1 - l, O.forces.f(top)[2] / a ** 2 / -firstPiola(l, s)[0, 0], width, s,
                                            qe.inverted["max"]))
    if l < 0.52:
        break
