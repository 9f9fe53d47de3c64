"""P-wave arrival in a laterally confined bar.

A bar of length 1 m and square section h x h, one cell across, with every
node's x and y blocked (uniaxial strain), is struck at z = -0.5 m: the end
face is driven at v0 from t = 0.  A step front travels at the constrained
(P-wave) speed

    c_P = sqrt((lambda + 2 mu) / rho) = sqrt(E (1 - nu) / ((1 + nu)(1 - 2 nu) rho))

(Achenbach, Wave Propagation in Elastic Solids, ch. 2).  The lateral
confinement makes this the exact continuum answer at every wavelength; an
unconfined bar would carry sqrt(E / rho) only for wavelengths much longer
than its thickness, and the sharp front has all wavelengths.  The front's
arrival (velocity crossing v0/2, interpolated between steps) at z = -0.25 and
+0.25 m gives the measured speed; error = measured / c_P - 1."""
import math

import numpy as np

import qdem
from acclib import LAW_LABELS, Stepper, lame

E, NU, RHO = 1e7, 0.3, 1000.0
LZ = 1.0


def cP():
    lam, mu = lame(E, NU)
    return math.sqrt((lam + 2 * mu) / RHO)


def run(cells=100, dtFraction=0.9, tetsPerCell=6, law="stableNeoHookean"):
    h = LZ / cells
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=0.0, radius=h / 4, law=law)
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((h, h, LZ), (1, 1, cells), tetsPerCell=tetsPerCell), mat, reorder=False)
    X = p.refPos
    p.blocked[:] = 3
    end = np.isclose(X[:, 2], -LZ / 2)
    v0 = 0.01
    p.blocked[end] = 7
    p.vel[end, 2] = v0
    c = cP()
    dt = dtFraction * w.stableDt()["combined"]
    stations = (-0.25, 0.25)
    idx = [np.where(np.isclose(X[:, 2], X[np.argmin(np.abs(X[:, 2] - z)), 2]))[0] for z in stations]
    zs = [X[i[0], 2] for i in idx]
    arrival = [None, None]
    prev = [0.0, 0.0]
    s = Stepper(w, dt)
    while arrival[1] is None:
        s(1)
        for k, i in enumerate(idx):
            v = p.vel[i, 2].mean()
            if arrival[k] is None and v >= 0.5 * v0:  # crossing between the last two steps
                arrival[k] = s.time - dt * (v - 0.5 * v0) / (v - prev[k])
            prev[k] = v
        if s.time > 3 * LZ / c:
            raise RuntimeError("pwave: no arrival")
    speed = (zs[1] - zs[0]) / (arrival[1] - arrival[0])
    return dict(error=speed / c - 1, value=speed, reference=c, h=h, wall=s.wall, steps=s.steps,
                nTets=w.core.nTets)


def cases(short):
    cs = [25, 50, 100, 200] if short else [25, 50, 100, 200, 400]
    out = [("element size", "1/%d m" % n, dict(cells=n)) for n in cs]
    out += [("time step", "%.2f dt_stable" % f, dict(cells=100, dtFraction=f)) for f in (0.25, 0.5, 0.9, 0.99)]
    out += [("tetsPerCell", "%d" % t, dict(cells=100, tetsPerCell=t)) for t in (5, 6, 12)]
    out += [("material law", LAW_LABELS[l], dict(cells=100, law=l)) for l in LAW_LABELS]
    return out


DEFAULTS = {"element size": None, "time step": "0.90 dt_stable", "tetsPerCell": "6",
            "material law": "stable Neo-Hookean"}
TITLE = "P-wave arrival in a confined bar"
ERROR = "front speed / c_P - 1"
