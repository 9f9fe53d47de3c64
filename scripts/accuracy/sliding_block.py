"""A block sliding with friction on a QDEM slab, and a block resting on a slope.

Sliding: a 0.1 m cube (E = 1e7 Pa, rho = 1000 kg/m^3, viscosity 2000 Pa s)
launched at 1 m/s along a fixed QDEM slab with piece-piece friction mu = 0.3
decelerates at (Coulomb's law of kinetic friction with the normal force equal
to the weight)

    a = mu g,

measured as the slope of the centre-of-mass velocity between t = 0.03 s (after
the landing transient) and 0.2 s; error = a / (mu g) - 1.

Stick: the same cube at rest on the slab under gravity tilted by
theta = atan(mu / 2), half the friction angle, must not move: the measured
quantity is the creep speed [m/s] of its centre between t = 0.1 and 0.3 s
(exact: 0).  A viscous-regularised law, Ft = -mu Fn vt / max(|vt|, vReg),
balances the slope only while sliding, at |vt| = vReg tan(theta) / mu."""
import math

import numpy as np

import qdem
from acclib import G, Stepper, setOptions

MU = 0.3


def _scene(cells, slope=0.0, v0=0.0, **options):
    mat = qdem.QdemMat(young=1e7, poisson=0.3, density=1000.0, viscosity=2000.0, radius=2e-3,
                       frictionPiece=MU, restitution=0.5)
    w = qdem.World()
    slab = w.addPiece(qdem.boxMesh((0.6, 0.3, 0.05), (12, 6, 1)), mat, pos=(0.2, 0, -0.025))
    slab.blocked[:] = 7
    block = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (cells,) * 3), mat, pos=(0, 0, 0.05 + 2 * mat.radius),
                       vel=(v0, 0, 0))
    w.core.gravity = (G * math.sin(slope), 0, -G * math.cos(slope))
    setOptions(w, **options)
    return w, block


def run(cells=3, dtFraction=0.8, **options):
    w, block = _scene(cells, v0=1.0, **options)
    dt = dtFraction * w.stableDt()["combined"]
    s = Stepper(w, dt)
    t, v = [], []
    while s.time < 0.2:
        s(max(1, int(0.005 / dt)))
        if s.time >= 0.03:
            t.append(s.time)
            v.append(block.velocity[0])
    a = -np.polyfit(t, v, 1)[0]
    return dict(error=a / (MU * G) - 1, value=a, reference=MU * G, wall=s.wall, steps=s.steps, edgeEdge=s.maxEdgeEdge,
                nTets=w.core.nTets)


def runStick(cells=3, dtFraction=0.8, **options):
    theta = math.atan(MU / 2)
    w, block = _scene(cells, slope=theta, **options)
    dt = dtFraction * w.stableDt()["combined"]
    s = Stepper(w, dt)
    s(int(0.1 / dt))
    x0, t0 = block.centroid[0], s.time
    s(int(0.2 / dt))
    creep = (block.centroid[0] - x0) / (s.time - t0)
    return dict(error=creep, value=creep, reference=0.0, wall=s.wall, steps=s.steps, edgeEdge=s.maxEdgeEdge, nTets=w.core.nTets)


FRICTION = [("spring (default)", dict(friction="spring")),
            ("regularized, vReg = 1e-3 m/s", dict(friction="regularized", vReg=1e-3)),
            ("regularized, vReg = 1e-2 m/s", dict(friction="regularized", vReg=1e-2))]
KINDS = [("point-polygon, face only (seed)", dict(regions=False, edgeEdge=False)),
         ("+ edge-edge", dict(regions=False, edgeEdge=True)),
         ("+ edge and vertex regions (default)", dict(regions=True, edgeEdge=True))]


def cases(short):
    out = [("friction model", k, kw) for k, kw in FRICTION]
    if not short:
        out += [("contact kinds", k, kw) for k, kw in KINDS]
        out += [("time step", "%.2f dt_stable" % f, dict(dtFraction=f)) for f in (0.3, 0.6, 0.8)]
        out += [("element size", "block 0.1/%d m" % n, dict(cells=n)) for n in (2, 3, 4)]
    return out


def stickCases(short):
    return [("friction model", k, kw) for k, kw in FRICTION]


DEFAULTS = {"friction model": "spring (default)", "contact kinds": "+ edge and vertex regions (default)",
            "time step": "0.80 dt_stable", "element size": "block 0.1/3 m"}
TITLE = "Block sliding with friction (mu g)"
ERROR = "deceleration / (mu g) - 1"
STICK_TITLE = "Block resting on a slope at half the friction angle"
STICK_ERROR = "creep speed [m/s] (exact 0)"
