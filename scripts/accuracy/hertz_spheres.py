"""Two QDEM spheres pressed together: force against indentation, Hertz.

Two equal spheres (R = 5 cm, E = 1e7 Pa, nu = 0.3, CGAL-meshed from an
icosphere to element size h) are driven together quasi-statically: the nodes
of each far cap (beyond 0.75 R from the centre) move at a prescribed
0.002 c_P, everything starts with that rigid velocity, local damping 0.3
keeps the bodies quasi-static (at half the speed the force changes by
< 0.5 %).  The indentation is the approach of the two centres (mean of the
nodes within 0.3 R of each centre) beyond first touch of the contact shells
(radius R + r, r the surface particle radius):

    d = 2 (R + r) - |c_B - c_A|

and the force is the contact force on one sphere (its nodal forces summed:
the element forces cancel).  Reference (Hertz 1882; Johnson, Contact
Mechanics, eq. 4.22):

    F = 4/3 E* sqrt(R*) d^{3/2},  1/E* = 2 (1 - nu^2) / E,  R* = (R + r) / 2

error = F / F_Hertz - 1 at d = 0.06 R (interpolated), where the contact
radius sqrt(R* d) is about 0.18 R.  Two biases do not vanish with h: the centres'
approach includes the compliance of the spheres' bodies (Hertz assumes
half-spaces), and the contact layer of penalty springs (kn = E r per node
pair) adds its own compliance."""
import math

import numpy as np

import qdem
from acclib import Stepper, icosphere, setOptions

E, NU, RHO, R = 1e7, 0.3, 1000.0, 0.05
D_EVAL = 0.06


def hertz(d, r):
    Es = E / (2 * (1 - NU ** 2))
    Rs = (R + r) / 2
    return 4.0 / 3.0 * Es * math.sqrt(Rs) * np.maximum(d, 0) ** 1.5


_meshes = {}


def sphereMesh(h):
    if h not in _meshes:
        _meshes[h] = qdem.meshSurface(icosphere(R, 4), h)
    return _meshes[h]


def run(nh=6, radius=1.0, dtFraction=0.9, speed=0.002, **options):
    h = R / nh
    r = radius * h
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=0.0, radius=r, frictionPiece=0.0,
                       restitution=1.0)
    msh = sphereMesh(h)
    w = qdem.World()
    gap0 = 0.002 * R
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    v = speed * math.sqrt((lam + 2 * mu) / RHO)
    a = w.addPiece(msh, mat, pos=(-(R + r + gap0), 0, 0), vel=(v, 0, 0))
    b = w.addPiece(msh, mat, pos=(R + r + gap0, 0, 0), vel=(-v, 0, 0))
    setOptions(w, **options)
    w.core.localDamping = 0.3
    centre = []
    for p, side in ((a, -1), (b, 1)):
        X = p.refPos - p.refPos.mean(0)
        p.blocked[side * X[:, 0] > 0.75 * R] = 7
        centre.append(np.linalg.norm(X, axis=1) < 0.3 * R)
    dt = dtFraction * w.stableDt()["combined"]
    dmax = 1.2 * D_EVAL * R
    nsteps = int((dmax + 2 * gap0) / (2 * v) / dt) + 1
    chunk = max(1, nsteps // 60)
    s = Stepper(w, dt)
    d, F = [], []
    while s.steps < nsteps:
        s(chunk)
        d.append(2 * (R + r) - (b.pos[centre[1], 0].mean() - a.pos[centre[0], 0].mean()))
        F.append(-a.force[:, 0].sum())
    d, F = np.array(d), np.array(F)
    dEval = D_EVAL * R
    Fm = float(np.interp(dEval, d, F))
    sel = (d > 0.02 * R) & (d < dmax) & (F > 0)
    exponent = float(np.polyfit(np.log(d[sel]), np.log(F[sel]), 1)[0]) if sel.sum() > 3 else float("nan")
    return dict(error=Fm / hertz(dEval, r) - 1, value=Fm, reference=float(hertz(dEval, r)), h=h,
                exponent=exponent, wall=s.wall, steps=s.steps, edgeEdge=s.maxEdgeEdge, nTets=w.core.nTets,
                curve=dict(d=(d / R).tolist(), F=F.tolist(), Fh=hertz(d, r).tolist()))


KINDS = [("point-polygon, face only (seed)", dict(regions=False, edgeEdge=False)),
         ("+ edge-edge", dict(regions=False, edgeEdge=True)),
         ("+ edge and vertex regions (default)", dict(regions=True, edgeEdge=True))]


def cases(short):
    ns = [4, 6, 8] if short else [4, 6, 8, 12, 16, 20]
    out = [("element size", "R/%d" % n, dict(nh=n)) for n in ns]
    nk = 6 if short else 8
    out += [("contact kinds", k + " (R/%d)" % nk, dict(nh=nk, **kw)) for k, kw in KINDS]
    out += [("contact radius", "r = %.2g h (R/%d)" % (f, nk), dict(nh=nk, radius=f)) for f in (0.5, 1.0, 2.0)]
    if not short:
        out += [("time step", "%.2f dt_stable (R/%d)" % (f, nk), dict(nh=nk, dtFraction=f)) for f in (0.3, 0.6, 0.9)]
        out += [("broad phase", "%s (R/%d)" % (m, nk), dict(nh=nk, broadPhase=m)) for m in ("A", "B", "C", "triangles")]
        out += [("loading speed", "%.4g c_P (R/%d)" % (f, nk), dict(nh=nk, speed=f)) for f in (0.001, 0.002, 0.004)]
    return out


DEFAULTS = {"contact kinds": "+ edge and vertex regions (default)", "contact radius": "r = 1 h",
            "time step": "0.90 dt_stable", "broad phase": "triangles", "loading speed": "0.002 c_P"}
TITLE = "Two spheres pressed together (Hertz)"
ERROR = "F / F_Hertz - 1 at d = 0.06 R"
