"""A free elastic block bouncing on the floor: energy balance.

A 0.1 m cube (E = 1e7 Pa, nu = 0.3, rho = 1000 kg/m^3, no viscosity, contact
restitution 1, wall friction 0.5) falls from 2 cm at 1 m/s, with 0.2 m/s
sideways and a 2 rad/s spin so that friction works, onto a YADE-style floor
wall and bounces.  Energy is conserved exactly in the continuum:

    E_kin + E_strain + E_contact springs - W_gravity + D_friction = const

(W_gravity = m g . (x - x0), D_friction the work of sliding friction, both
kept by the engine's ledger, doc/formulation.md §2).  The error is the
largest departure of that sum from its start over 0.08 s (fall, impact,
rebound), relative to the energy brought to the floor, E_kin0 + m g * 2 cm."""
import numpy as np

import qdem
from acclib import G, LAW_LABELS, Stepper, floor

V0, DROP, L = 1.0, 0.02, 0.1


def run(cells=3, dtFraction=0.8, tetsPerCell=6, law="stableNeoHookean"):
    mat = qdem.QdemMat(young=1e7, poisson=0.3, density=1000.0, viscosity=0.0, radius=2e-3, restitution=1.0, law=law,
                       frictionWall=0.5)
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((L, L, L), (cells,) * 3, tetsPerCell=tetsPerCell), mat,
                   pos=(0, 0, L / 2 + mat.radius + DROP), vel=(0.2, 0, -V0), angVel=(0, 2.0, 0))
    floor(w)
    w.core.gravity = (0, 0, -G)
    w.core.trackEnergy = True
    dt = dtFraction * w.stableDt()["combined"]
    s = Stepper(w, dt)
    s(1)
    e0 = w.core.energy["total"]
    m = p.totalMass
    scale = 0.5 * m * (V0 ** 2 + 0.2 ** 2) + m * G * DROP
    worst, chunk = 0.0, max(1, int(2e-4 / dt))
    while s.time < 0.08:
        s(chunk)
        worst = max(worst, abs(w.core.energy["total"] - e0))
    return dict(error=worst / scale, value=worst, reference=0.0, h=L / cells, wall=s.wall, steps=s.steps,
                nTets=w.core.nTets, bounced=bool(p.velocity[2] > 0))


def cases(short):
    fs = (0.25, 0.5, 0.9) if short else (0.1, 0.25, 0.5, 0.8, 0.9, 0.99)
    out = [("time step", "%.2f dt_stable" % f, dict(dtFraction=f)) for f in fs]
    if not short:
        out += [("element size", "0.1/%d m" % n, dict(cells=n)) for n in (2, 3, 4, 6, 8)]
        out += [("tetsPerCell", "%d" % t, dict(tetsPerCell=t)) for t in (5, 6, 12)]
    out += [("material law", LAW_LABELS[l], dict(law=l)) for l in LAW_LABELS]
    return out


DEFAULTS = {"time step": "0.80 dt_stable", "element size": "0.1/3 m", "tetsPerCell": "6",
            "material law": "stable Neo-Hookean"}
TITLE = "Elastic block bouncing on the floor (energy balance)"
ERROR = "max |energy ledger drift| / energy brought in"
