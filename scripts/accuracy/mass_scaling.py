"""What selective mass scaling costs in accuracy and saves in time.

Meshes with slivers (a node moved 97 % of the way to the face opposite it
in one of its tets: that tet and the ones sharing its face's plane become
slivers, height / longest edge 0.012 against 0.41 elsewhere), each run twice:
WITHOUT mass scaling, at the step the slivers leave (0.8 x stableDt), and
WITH addPiece(targetDt=...), targetDt the element step the same mesh would
have without its slivers or, when that costs more, the largest step that
the default budget (maxAddedMass = 1 %) buys, at 0.8 x the step it
then gets.  Four problems:

- P-wave: the front speed in a laterally confined bar (scripts/accuracy/
  pwave_bar.py) with a sliver between its two stations, against c_P.
- bounce: a viscoelastic cube with an interior sliver dropped at 1 m/s on a
  floor: the restitution (rebound / impact speed of the centre of mass).
- fall time: the same cube released 5 cm above the floor: the time to the
  first floor contact, against sqrt(2 d / g).
- domino pair: two standing blocks (shogi-piece-like, 15 x 50 x 80 mm, a
  sliver inside each), the first released tipped past its tipping angle
  towards the second: the time the second reaches 45 degrees.

The error of each WITH run is against the WITHOUT run of the same mesh (and
against the analytic value where there is one); the saving is the ratio of
steps and of wall time.

    mass_scaling.py [--out DIR] [--table JSON]

writes DIR/mass_scaling.json (default out/accuracy) and prints the Markdown
table of doc/accuracy.md; --table JSON prints the table of a saved run
(bench/logs/mass_scaling.json) without running anything."""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import qdem  # noqa: E402
from acclib import G, Stepper, floor, lame, oneThread  # noqa: E402

SQUASH = 0.97


def sliverize(mesh, near=(0.0, 0.0, 0.0), squash=SQUASH, interior=True):
    """(nodes, tets) of `mesh` with the node nearest `near` (an interior node
    unless interior=False) moved `squash` of its height towards the face
    opposite it in the first of its tets that stays positive."""
    x, t = np.array(mesh.nodes, dtype=float), np.array(mesh.tets)
    lo, hi = x.min(axis=0), x.max(axis=0)
    inside = np.all((x > lo + 1e-9) & (x < hi - 1e-9), axis=1) if interior else np.ones(len(x), bool)
    cand = np.where(inside)[0]
    node = cand[np.argmin(np.linalg.norm(x[cand] - np.asarray(near), axis=1))]
    for tet in np.where((t == node).any(axis=1))[0]:
        a, b, c = x[[v for v in t[tet] if v != node]]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        y = x.copy()
        y[node] -= squash * np.dot(x[node] - a, n) * n
        A, B, C, D = (y[t[:, k]] for k in range(4))
        if (np.einsum("ij,ij->i", B - A, np.cross(C - A, D - A)) > 0).all():
            return y, t
    raise RuntimeError("no tet to flatten")


def targetFor(regular, mesh, mat, budget=0.01):
    """The targetDt of the study: the element step the mesh would allow
    without its slivers (`regular`'s viscous step), or, when that needs more,
    the largest step that the default budget (maxAddedMass=1 %) buys
    (bisection on World.core.massScaling)."""
    w = qdem.World()
    w.addPiece(regular, mat)
    hi = w.stableDt()["viscous"]
    x, t = mesh
    index = w.materialIndex(mat)
    own = mat.density * np.abs(np.einsum("ij,ij->i", x[t[:, 1]] - x[t[:, 0]],
                                         np.cross(x[t[:, 2]] - x[t[:, 0]], x[t[:, 3]] - x[t[:, 0]]))).sum() / 6

    def fraction(dt):
        return w.core.massScaling(x, t, index, dt).sum() / own
    if fraction(hi) <= budget:
        return hi
    lo = hi / 1e4
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if fraction(mid) <= budget else (lo, mid)
    return lo


def add(w, mesh, mat, scaled, target, **kw):
    extra = dict(targetDt=target, maxAddedMass=0.01 + 1e-9) if scaled else {}
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (surface mass: reported in the table)
        return w.addPiece(mesh, mat, **kw, **extra)


# ---------------------------------------------------------------------------
E, NU, RHO = 1e6, 0.3, 1000.0


def pwave(scaled, cells=40, LZ=1.0):
    h = LZ / cells
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=0.0, radius=h / 4)
    regular = qdem.boxMesh((2 * h, 2 * h, LZ), (2, 2, cells))
    mesh = sliverize(regular)
    w = qdem.World()
    p = add(w, mesh, mat, scaled, targetFor(regular, mesh, mat), reorder=False)
    X = p.refPos
    p.blocked[:] = 3
    end = np.isclose(X[:, 2], -LZ / 2)
    v0 = 0.01
    p.blocked[end] = 7
    p.vel[end, 2] = v0
    lam, mu = lame(E, NU)
    c = math.sqrt((lam + 2 * mu) / RHO)
    dt = 0.8 * w.stableDt()["combined"]
    zs = (-0.25, 0.25)
    idx = [np.where(np.isclose(X[:, 2], z))[0] for z in zs]
    arrival, prev = [None, None], [0.0, 0.0]
    s = Stepper(w, dt)
    while arrival[1] is None:
        s(1)
        for k, i in enumerate(idx):
            v = p.vel[i, 2].mean()
            if arrival[k] is None and v >= 0.5 * v0:
                arrival[k] = s.time - dt * (v - 0.5 * v0) / (v - prev[k])
            prev[k] = v
        if s.time > 3 * LZ / c:
            raise RuntimeError("pwave: no arrival")
    speed = (zs[1] - zs[0]) / (arrival[1] - arrival[0])
    return dict(value=speed, analytic=c, steps=s.steps, wall=s.wall, dt=dt, added=p.addedMassFraction,
                target=p.targetDt,
                nodeShare=p.addedMassMaxNodeShare, nTets=w.core.nTets)


def cube(mat, scaled, cells=4, L=0.1, **kw):
    regular = qdem.boxMesh((L, L, L), (cells,) * 3)
    mesh = sliverize(regular)
    w = qdem.World()
    p = add(w, mesh, mat, scaled, targetFor(regular, mesh, mat), **kw)
    floor(w)
    w.core.gravity = (0, 0, -G)
    return w, p


def bounce(scaled):
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=20.0, radius=2e-3, restitution=0.5,
                       frictionWall=0.0)
    w, p = cube(mat, scaled, pos=(0, 0, 0.05 + mat.radius + 1e-3), vel=(0, 0, -1.0))
    dt = 0.8 * w.stableDt()["combined"]
    s = Stepper(w, dt)
    vin, chunk = None, max(1, int(2e-5 / dt))
    touched = False
    while s.time < 0.1:
        s(chunk)
        f = abs(w.core.obstacleReactions()[0][2])
        vz = p.velocity[2]
        if f > 0 and not touched:
            touched, vin = True, -vz
        if touched and f == 0:
            break
    return dict(value=p.velocity[2] / vin, analytic=None, steps=s.steps, wall=s.wall, dt=dt, target=p.targetDt,
                added=p.addedMassFraction, nodeShare=p.addedMassMaxNodeShare, nTets=w.core.nTets)


def fall(scaled, gap=0.05):
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=20.0, radius=2e-3, restitution=0.5)
    w, p = cube(mat, scaled, pos=(0, 0, 0.05 + mat.radius + gap))
    dt = 0.8 * w.stableDt()["combined"]
    s = Stepper(w, dt)
    while w.core.obstacleReactions()[0][2] == 0:
        s(1)
        if s.time > 1:
            raise RuntimeError("fall: no contact")
    # The touch happened within the last step: its middle.
    return dict(value=s.time - 0.5 * dt, analytic=math.sqrt(2 * gap / G), steps=s.steps, wall=s.wall, dt=dt,
                target=p.targetDt,
                added=p.addedMassFraction, nodeShare=p.addedMassMaxNodeShare, nTets=w.core.nTets)


def domino(scaled, T=0.015, W=0.05, H=0.08, gap=0.065):
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=2.0, radius=1.5e-3, restitution=0.3,
                       frictionWall=0.5, frictionPiece=0.3)
    regular = qdem.boxMesh((T, W, H), (2, 4, 6))
    mesh = sliverize(regular)
    target = targetFor(regular, mesh, mat)
    w = qdem.World()
    z = H / 2 + mat.radius
    # The first block starts at rest tipped by 12 degrees (past its tipping
    # angle atan(T / H) = 10.6 degrees) on its edge x = T/2, towards the second.
    th = math.radians(12.0)
    first = add(w, mesh, mat, scaled, target, ori=((0, 1, 0), th),
                pos=(T / 2 * (1 - math.cos(th)) + H / 2 * math.sin(th), 0,
                     T / 2 * math.sin(th) + H / 2 * math.cos(th) + mat.radius))
    second = add(w, mesh, mat, scaled, target, pos=(gap, 0, z))
    floor(w)
    w.core.gravity = (0, 0, -G)
    X = second.refPos
    top, bottom = X[:, 2] > X[:, 2].max() - 1e-9, X[:, 2] < X[:, 2].min() + 1e-9
    dt = 0.8 * w.stableDt()["combined"]
    s = Stepper(w, dt)
    chunk = max(1, int(2e-4 / dt))
    tilt = 0.0
    while tilt < 45:
        s(chunk)
        x = np.array(second.pos)
        axis = x[top].mean(axis=0) - x[bottom].mean(axis=0)
        tilt = math.degrees(math.acos(axis[2] / np.linalg.norm(axis)))
        if s.time > 2:
            raise RuntimeError("domino: the second block did not fall")
    return dict(value=s.time, analytic=None, steps=s.steps, wall=s.wall, dt=dt, added=first.addedMassFraction,
                target=first.targetDt,
                nodeShare=first.addedMassMaxNodeShare, nTets=w.core.nTets)


PROBLEMS = {
    "P-wave": (pwave, "front speed [m/s]"),
    "bounce": (bounce, "restitution"),
    "fall time": (fall, "time to the floor [s]"),
    "domino pair": (domino, "time to 45 deg of the 2nd block [s]"),
}


def table(res):
    lines = ["| problem | quantity | without: value | with: value | error with vs without | error vs analytic "
             "(without / with) | added mass (largest node share) | step without / with [s] | steps saved | "
             "wall time without / with [s] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, r in res.items():
        a, b = r["without"], r["with"]
        err = b["value"] / a["value"] - 1
        an = "-" if a["analytic"] is None else "%+.2e / %+.2e" % (a["value"] / a["analytic"] - 1,
                                                                  b["value"] / b["analytic"] - 1)
        lines.append("| %s | %s | %.5g | %.5g | %+.2e | %s | %.2f %% (%.3g) | %.2e / %.2e | x%.1f (%d -> %d) | "
                     "%.2f / %.2f |" % (name, PROBLEMS[name][1], a["value"], b["value"], err, an,
                                        100 * b["added"], b["nodeShare"], a["dt"], b["dt"],
                                        a["steps"] / b["steps"], a["steps"], b["steps"], a["wall"], b["wall"]))
    return "\n".join(lines)


def section(data):
    """Markdown for doc/accuracy.md from the JSON this script writes."""
    res = data["results"]
    t = ["## Selective mass scaling\n",
         "`scripts/accuracy/mass_scaling.py` (raw numbers: `out/accuracy/mass_scaling.json`, committed as "
         "`bench/logs/mass_scaling.json`; `mass_scaling.py --table bench/logs/mass_scaling.json` prints this table "
         "again).  Meshes with slivers (one node moved %d %% of the way to the face opposite it: the tets sharing "
         "that face's plane become slivers, height / longest edge about 0.012 against 0.41 elsewhere), run "
         "WITHOUT mass scaling at 0.8 x the step the slivers leave, and WITH `addPiece(targetDt=...)` at 0.8 x "
         "the step it gives; `targetDt` is the element step of the same mesh without its slivers, or the largest "
         "step that the default `maxAddedMass` (1 %%) buys when that costs more (doc/meshes.md, \"Selective mass "
         "scaling\").  The error is the WITH value against the WITHOUT value of the same mesh, and each against "
         "the analytic value where there is one.  Steps and wall time (one thread, shared machine) of the "
         "stepping alone.\n" % round(100 * data["squash"]),
         table(res), "",
         "- P-wave: the front crosses the heavier nodes around the slivers (an impedance step; the largest "
         "node share is the added mass at one node over its own): its mean speed between the stations drops; the "
         "drop grows with the added mass per unit length of the bar.",
         "- bounce: the restitution moves only as much as the block's inertia and its vibration modes do.",
         "- fall time: the added mass is real mass that gravity pulls on, so the fall itself is unchanged; what "
         "differs is how finely the larger step resolves the moment of touching (half a step).",
         "- domino pair: the blocks topple as slightly heavier bodies (the slivers sit inside them); the figure "
         "also holds the larger step's own error on the contact sequence (edge on face, then rocking).",
         "", "Removing the slivers instead (`qdem.improveMesh`) costs none of these errors.", ""]
    return "\n".join(t) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/accuracy")
    ap.add_argument("--table", help="print the table of a saved JSON and stop")
    ap.add_argument("--only", nargs="*", help="run only these problems (%s)" % ", ".join(PROBLEMS))
    a = ap.parse_args(argv)
    if a.table:
        with open(a.table) as f:
            print(section(json.load(f)))
        return
    oneThread()
    res = {}
    for name, (fn, _) in PROBLEMS.items():
        if a.only and name not in a.only:
            continue
        res[name] = {}
        for scaled in (False, True):
            t = time.time()
            r = fn(scaled)
            res[name]["with" if scaled else "without"] = r
            print("mass scaling %-12s %-7s value %.6g  %d steps  %.2f s  added %.3g %%  (%.0f s)"
                  % (name, "with" if scaled else "without", r["value"], r["steps"], r["wall"], 100 * r["added"],
                     time.time() - t), flush=True)
    os.makedirs(a.out, exist_ok=True)
    out = os.path.join(a.out, "mass_scaling.json")
    with open(out, "w") as f:
        json.dump({"squash": SQUASH, "threads": 1, "results": res}, f, indent=1)
    print(section({"squash": SQUASH, "results": res}))
    print("written", out)


if __name__ == "__main__":
    main()
