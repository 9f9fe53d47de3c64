"""Cantilever under its own weight: static tip deflection against beam theory.

Square beam L x b x b (L/b = 10), clamped at x = 0 (all DOFs of the end
face), gravity -z.  Reference: Timoshenko beam under a uniform load w = rho g A,

    delta = w L^4 / (8 E I) + w L^2 / (2 kappa G A),   I = b^4/12,
    kappa = 10 (1 + nu) / (12 + 11 nu)  (Cowper's shear coefficient, square section)

(Euler-Bernoulli term plus the shear term, 1 % of it at L/b = 10).  The
static state is reached by dynamic relaxation with local damping 0.8 (the
damping changes the path, not the equilibrium); the study knobs are the
element size (cells through the thickness) and tetsPerCell."""
import math

import numpy as np

import qdem
from acclib import G, LAW_LABELS, Stepper

E, NU, RHO = 1e8, 0.3, 1000.0
L, B = 0.2, 0.02


def reference():
    I, A = B ** 4 / 12, B * B
    w = RHO * G * A
    Gs = E / (2 * (1 + NU))
    kappa = 10 * (1 + NU) / (12 + 11 * NU)
    return w * L ** 4 / (8 * E * I) + w * L ** 2 / (2 * kappa * Gs * A)


def run(n=2, tetsPerCell=6, dtFraction=0.9, law="stableNeoHookean"):
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=0.0, radius=B / n / 4, law=law)
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((L, B, B), (10 * n, n, n), tetsPerCell=tetsPerCell), mat, pos=(L / 2, 0, 0))
    X = p.refPos
    p.blocked[np.isclose(X[:, 0], 0)] = 7
    tip = np.isclose(X[:, 0], L)
    w.core.gravity = (0, 0, -G)
    w.core.localDamping = 0.8
    dt = dtFraction * w.stableDt()["combined"]
    I, A = B ** 4 / 12, B * B
    T1 = 2 * math.pi / 1.875 ** 2 * L ** 2 * math.sqrt(RHO * A / (E * I))  # first bending period
    chunk = max(10, int(T1 / dt / 8))
    s = Stepper(w, dt)
    hist = []
    while True:
        s(chunk)
        hist.append(-p.displacement[tip, 2].mean())
        # converged: the tip moved less than 1e-5 of its deflection over a period
        if len(hist) > 8 and max(hist[-8:]) - min(hist[-8:]) < 1e-5 * abs(hist[-1]):
            break
        if s.steps > 5e6:
            raise RuntimeError("cantilever: no static state after %d steps" % s.steps)
    ref = reference()
    return dict(error=hist[-1] / ref - 1, value=hist[-1], reference=ref, h=B / n, wall=s.wall, steps=s.steps,
                nTets=w.core.nTets)


def cases(short):
    ns = [1, 2, 3] if short else [1, 2, 3, 4, 6, 8]
    out = [("element size", "b/%d" % n, dict(n=n)) for n in ns]
    nt = 2 if short else 4
    out += [("tetsPerCell", "%d (b/%d)" % (t, nt), dict(n=nt, tetsPerCell=t)) for t in (5, 6, 12)]
    out += [("material law", "%s (b/%d)" % (LAW_LABELS[l], nt), dict(n=nt, law=l)) for l in LAW_LABELS]
    return out


DEFAULTS = {"element size": None, "tetsPerCell": "6", "material law": "stable Neo-Hookean"}
TITLE = "Cantilever tip deflection under gravity"
ERROR = "tip deflection / Timoshenko beam - 1"
