"""A soft Kelvin-Voigt ball rolling on a rigid floor: its rolling friction
against Brilliantov & Poeschel's theory, per dissipation channel, and against
mesh refinement.

Ball: radius R = 0.15 m, E = 0.5 MPa, nu = 0.3, rho = 1000 kg/m^3, viscosity
eta = 200 Pa s (QdemMat.viscosity), node contact radius 8 mm, restitution 0.3,
a qdem.ballMesh at element size h; the floor is a YADE-style wall facing +z.
The ball first settles on the floor at rest (0.3 s with local damping, then
0.05 s without), then every node is given the velocity of rolling without
slip at V0 along x (v = V0 e_x + omega x (x - c), omega = V0/R e_y) and the
ball rolls for T seconds.

Theory (Brilliantov & Poeschel, Europhys. Lett. 42 (1998) 511): a viscoelastic
sphere rolling slowly on a hard plane (deformation small, V far below the
sound speed, xi/V far above the viscous relaxation time) feels the rolling
torque

    M = A V F_N,       i.e. a force at its centre mu_roll F_N, mu_roll = A V / R,

with F_N = m g and A the dissipative constant of the viscoelastic Hertz
contact (Brilliantov et al., Phys. Rev. E 53 (1996) 5382):

    A = (1/3) (3 eta2 - eta1)^2 / (3 eta2 + 2 eta1) * (1 - nu^2)(1 - 2 nu) / (E nu^2),

eta1, eta2 the shear and bulk viscosities of sigma' = eta1 (de/dt - tr(de/dt) I/3)
+ eta2 tr(de/dt) I.  QDEM's viscous stress is beta (lambda tr(dE/dt) I +
2 mu dE/dt), beta = eta/mu (doc/formulation.md), so eta1 = 2 beta mu = 2 eta and
eta2 = beta K: then 3 eta2 - eta1 = 3 beta lambda, 3 eta2 + 2 eta1 = 3 beta (lambda + 2 mu),
and A = beta exactly.  (As it must: when the viscous stress is beta times the
rate of the elastic stress, every quasi-static force is F + beta dF/dt.)
A rolling ball (I = 2/5 m R^2, kinetic energy 7/10 m V^2) loses dE/dt = -M V/R:

    dV/dt = -(5/7) beta g V / R,        V = V0 exp(-t/tau), tau = 7 R / (5 beta g),

tau = 20.6 s for the ball above (beta = 1.04 ms), whatever V0 (its kinetic
energy e-folds in tau/2 = 10.3 s).

Measured: the dissipated power P per ledger channel (bulk viscosity,
contact dashpots, friction) over the roll, as a rolling-resistance lever arm
d = P / (F_N omega) against the theory's d = beta V (the ratio
P/P_theory); the centre's deceleration (slope of V(t)) against
(5/7) beta g V / R.  A polyhedral ball also loses energy where its facets
meet the floor (node contact dashpots, friction of the nodes that land):
the same roll with viscosity 0 measures that part alone.

Dropped (--drop): the same ball (h = 0.075 m) dropped from 0.1 m at rest;
after the bounces it rolls and rocks at a few cm/s, and the mechanical
energy it loses in 6-10 s and 10-14 s is set against beta F_N V^2 / R along
its measured motion (bench/logs/rolling_ball_drop.json; 5 min).

Writes bench/logs/rolling_ball.json and doc/img/rolling_ball.png.
Run: PYTHONPATH=build/python yade -n -x scripts/accuracy/rolling_ball.py [--short | --plot | --drop]
(or with /usr/bin/python3.11); about 15 min on one thread (--short: one
0.5 s roll, nothing written; --plot: the figure from the kept JSON)."""
import json
import os
import sys

# yade -x runs the script with __file__ naming yade itself: then sys.argv[0] is the script
HERE = os.path.dirname(os.path.abspath(__file__ if __file__.endswith("rolling_ball.py") else sys.argv[0]))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import qdem  # noqa: E402
from acclib import G, Stepper, floor, lame, oneThread  # noqa: E402

R, E, NU, RHO, ETA = 0.15, 0.5e6, 0.3, 1000.0, 200.0
NODE_RADIUS, RESTITUTION = 0.008, 0.3
SETTLE = 0.3  # s of settling at rest with local damping before the launch
LOG = os.path.join(HERE, "../../bench/logs/rolling_ball.json")
DROP_LOG = os.path.join(HERE, "../../bench/logs/rolling_ball_drop.json")
PNG = os.path.join(HERE, "../../doc/img/rolling_ball.png")


def beta(eta=ETA, young=E, nu=NU):
    """Kelvin-Voigt time constant beta = eta / mu [s]."""
    return eta / lame(young, nu)[1]


def dissipativeConstant(eta1, eta2, young=E, nu=NU):
    """Brilliantov et al.'s A [s] from the shear (eta1) and bulk (eta2)
    viscosities of sigma' = eta1 (de/dt - tr I/3) + eta2 tr(de/dt) I."""
    return ((3 * eta2 - eta1) ** 2 / (3 * (3 * eta2 + 2 * eta1)) * (1 - nu ** 2) * (1 - 2 * nu) / (young * nu ** 2))


def qdemViscosities(eta=ETA, young=E, nu=NU):
    """(eta1, eta2) of QDEM's Kelvin-Voigt stress in Brilliantov et al.'s
    notation: eta1 = 2 beta mu, eta2 = beta K."""
    lam, mu = lame(young, nu)
    b = eta / mu
    return 2 * b * mu, b * (lam + 2 * mu / 3)


def facetSize(piece):
    """Mean edge length [m] of the piece's surface triangles."""
    x, t = piece.pos, piece.surface()["triangles"]
    return float(np.mean([np.linalg.norm(x[t[:, i]] - x[t[:, (i + 1) % 3]], axis=1).mean() for i in range(3)]))


def settledBall(h, eta=ETA, implicit=True):
    """A ballMesh ball of element size h settled at rest on the floor.
    Returns (world, piece, dt, stepper)."""
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, radius=NODE_RADIUS, restitution=RESTITUTION, viscosity=eta)
    w = qdem.World()
    floor(w)
    p = w.addPiece(qdem.ballMesh(R, h), mat, pos=(0, 0, R + NODE_RADIUS - 0.004))
    w.core.gravity = (0, 0, -G)
    if implicit and eta > 0:
        w.core.viscousIntegration = 1  # implicit: the step is the elastic one, not the slivers' viscous one
    w.core.trackEnergy = True
    sd = w.stableDt()
    dt = 0.8 * (sd["combinedImplicit"] if implicit and eta > 0 else sd["combined"])
    s = Stepper(w, dt)
    w.core.localDamping = 0.3
    s(int(SETTLE / dt))
    w.core.localDamping = 0.0
    s(int(0.05 / dt))
    return w, p, dt, s


def launch(piece, V0):
    """Rolling without slip at V0 along +x: v = V0 e_x + (V0/R) e_y x (x - c)."""
    c = piece.centroid
    piece.vel[:] = np.array([V0, 0.0, 0.0]) + np.cross(np.array([0.0, V0 / R, 0.0]), piece.pos - c)


def spin(piece):
    """The ball's spin about y [rad/s] from its angular momentum about the centroid."""
    return piece.angularMomentumAbout(piece.centroid)[1] / (0.4 * piece.totalMass * R * R)


CHANNELS = ("viscous", "contactDamping", "friction")


def roll(h, V0=0.3, T=1.0, eta=ETA, sample=0.02):
    """Roll the settled ball at V0 for T s; returns the time series and the
    dissipated energy per channel."""
    w, p, dt, s = settledBall(h, eta)
    launch(p, V0)
    e0 = w.core.energy
    t0, wall0 = s.time, s.wall
    every = max(1, int(sample / dt))
    ts, vs, ws, ks, dis, tot = [], [], [], [], {c: [] for c in CHANNELS}, []
    while s.time - t0 < T - 1e-9:
        s(every)
        e = w.core.energy
        ts.append(s.time - t0)
        vs.append(float(p.velocity[0]))
        ws.append(float(spin(p)))
        ks.append(float(e["kinetic"]))
        tot.append(float(e["total"]))  # the ledger's sum: constant (the launch's kinetic energy is in it from the first sample)
        for c in CHANNELS:
            dis[c].append(float(e[c] - e0[c]))
    m = p.totalMass
    return dict(h=h, V0=V0, T=T, eta=eta, nTets=int(w.core.nTets), nNodes=int(len(p.pos)), facet=facetSize(p),
                mass=float(m), dt=dt,
                wall=s.wall - wall0, t=ts, V=vs, omega=ws, kinetic=ks, dissipated=dis,
                ledgerDrift=float(max(tot) - min(tot)))


def analyse(r):
    """Measured dissipated power per channel and deceleration against theory."""
    t, V = np.array(r["t"]), np.array(r["V"])
    b = beta(r["eta"]) if r["eta"] > 0 else beta(ETA)  # the elastic ball is compared with eta = 200's theory
    Vm = float(V.mean())
    FN, omega = r["mass"] * G, Vm / R
    Ptheory = b * Vm * FN * omega  # M omega, M = beta V F_N
    ok = t >= 0.1  # after the launch transient
    P = {c: float(np.polyfit(t[ok], np.array(r["dissipated"][c])[ok], 1)[0]) for c in CHANNELS}
    Ptot = sum(P.values())
    a = -float(np.polyfit(t[ok], V[ok], 1)[0])
    aTheory = 5.0 / 7.0 * b * G * Vm / R
    slip = float(np.mean(np.abs(np.array(r["V"]) - np.array(r["omega"]) * R)))
    return dict(Vmean=Vm, Ptheory=Ptheory, P=P, Ptotal=Ptot, ratio=Ptot / Ptheory,
                ratioViscous=P["viscous"] / Ptheory, lever=Ptot / (FN * omega), leverTheory=b * Vm,
                decel=a, decelTheory=aTheory, decelRatio=a / aTheory, meanSlip=slip)


def drop(h=0.075, height=0.1, T=16.0, sample=0.02, windows=((6.0, 10.0), (10.0, 14.0))):
    """The ball dropped from `height` [m] at rest: after the bounces it rolls
    and rocks at a few cm/s.  Per time window: the mechanical energy lost
    (kinetic + elastic + gravity + contact springs) and per channel, against
    the theory's beta F_N V^2 / R integrated along the measured horizontal
    speed V of the centre."""
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, radius=NODE_RADIUS, restitution=RESTITUTION, viscosity=ETA)
    w = qdem.World()
    floor(w)
    p = w.addPiece(qdem.ballMesh(R, h), mat, pos=(0, 0, height + R + NODE_RADIUS))
    w.core.gravity = (0, 0, -G)
    w.core.viscousIntegration = 1
    w.core.trackEnergy = True
    dt = 0.8 * w.stableDt()["combinedImplicit"]
    s = Stepper(w, dt)
    FN, b = p.totalMass * G, beta()
    every = max(1, int(sample / dt))
    rows, bp = [], 0.0
    while s.time < T - 1e-9:
        s(every)
        e = w.core.energy
        V = float(np.hypot(p.velocity[0], p.velocity[1]))
        bp += b * FN * V * V / R * every * dt
        rows.append([s.time, e["kinetic"], e["kinetic"] + e["elastic"] + e["gravity"] + e["contactElastic"], V, bp] +
                    [e[c] for c in CHANNELS])
    a = np.array(rows)
    out = dict(h=h, height=height, nTets=int(w.core.nTets), wall=s.wall,
               columns=["t", "kinetic", "mechanical", "V", "theoryDissipated"] + list(CHANNELS), rows=rows, windows=[])
    for t0, t1 in windows:
        i, j = np.searchsorted(a[:, 0], t0), np.searchsorted(a[:, 0], t1)
        lost, theory = a[i, 2] - a[j, 2], a[j, 4] - a[i, 4]
        out["windows"].append(dict(t0=t0, t1=t1, lost=lost, theory=theory, ratio=lost / theory,
                                   meanV=float(a[i:j, 3].mean()), maxKinetic=float(a[i:j, 1].max()),
                                   channels={c: float(a[j, 5 + k] - a[i, 5 + k]) for k, c in enumerate(CHANNELS)}))
        print("dropped ball, %g-%g s: mean V %.3g m/s, mechanical energy lost %.3g J = %.2f x B&P along the motion "
              "(%.3g J), kinetic energy at most %.3g J" % (t0, t1, out["windows"][-1]["meanV"], lost, lost / theory,
                                                           theory, out["windows"][-1]["maxKinetic"]), flush=True)
    return out


def cases(short):
    if short:
        return [dict(h=0.1, V0=0.3, T=0.5)]
    return ([dict(h=h, V0=0.3, T=1.0) for h in (0.1, 0.075, 0.03, 0.02, 0.015)] +
            [dict(h=0.03, V0=0.1, T=1.0), dict(h=0.03, V0=0.3, T=1.0, eta=0.0), dict(h=0.015, V0=0.3, T=1.0, eta=0.0)])


def label(r):
    return "h = %.3g m (facets %.3g m), V0 = %.2g m/s, eta = %g Pa s" % (r["h"], r["facet"], r["V0"], r["eta"])


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for r in results:
        t, V = np.array(r["t"]), np.array(r["V"])
        ax1.plot(t, V / r["V0"], label=label(r))
    tt = np.linspace(0, max(r["T"] for r in results), 50)
    tau = 7 * R / (5 * beta() * G)
    ax1.plot(tt, np.exp(-tt / tau), "k--", lw=2, label="B&P: exp(-t/tau), tau = 7R/(5 beta g) = %.1f s" % tau)
    ax1.set_xlabel("time after launch [s]")
    ax1.set_ylabel("V / V0")
    ax1.legend(fontsize=7)
    ax1.set_title("speed of the ball's centre")
    names = [("viscous", "bulk viscosity"), ("contactDamping", "contact dashpots"), ("friction", "friction")]
    x = np.arange(len(results))
    bottom = np.zeros(len(results))
    for key, name in names:
        vals = np.array([r["analysis"]["P"][key] / r["analysis"]["Ptheory"] for r in results])
        ax2.bar(x, vals, bottom=bottom, label=name)
        bottom += vals
    ax2.axhline(1.0, color="k", ls="--", label="B&P: P = beta V F_N omega")
    ax2.set_xticks(x)
    ax2.set_xticklabels(["h %.3g\nV0 %.2g\neta %g" % (r["h"], r["V0"], r["eta"]) for r in results], fontsize=8)
    ax2.set_ylabel("dissipated power / B&P (eta = 200)")
    ax2.set_ylim(0, 1.75)
    ax2.legend(fontsize=8, loc="upper right")
    ax2.set_title("rolling dissipation by channel")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv):
    short = "--short" in argv
    if "--drop" in argv:  # the ball dropped from 0.1 m, as in tests/python/test_soft_drops.py
        oneThread()
        with open(DROP_LOG, "w") as f:
            json.dump(drop(), f)
        return
    if "--plot" in argv:  # the figure again from the kept JSON, without running
        with open(LOG) as f:
            plot(json.load(f)["runs"], PNG)
        return
    oneThread()
    b = beta()
    eta1, eta2 = qdemViscosities()
    out = dict(R=R, E=E, nu=NU, rho=RHO, eta=ETA, beta=b, eta1=eta1, eta2=eta2, A=dissipativeConstant(eta1, eta2),
               tau=7 * R / (5 * b * G), runs=[])
    for kw in cases(short):
        r = roll(**kw)
        r["analysis"] = analyse(r)
        out["runs"].append(r)
        a = r["analysis"]
        print("%s: %d tets, P/P_BP = %.2f (viscous %.2f, dashpots %.2f, friction %.2f), decel %.4g vs %.4g m/s^2, "
              "slip %.2g m/s, ledger drift %.2g J, %.0f s" %
              (label(r), r["nTets"], a["ratio"], a["P"]["viscous"] / a["Ptheory"],
               a["P"]["contactDamping"] / a["Ptheory"], a["P"]["friction"] / a["Ptheory"], a["decel"],
               a["decelTheory"], a["meanSlip"], r["ledgerDrift"], r["wall"]), flush=True)
    if not short:
        with open(LOG, "w") as f:
            json.dump(out, f, indent=1)
        plot(out["runs"], PNG)
        print("wrote", os.path.normpath(LOG), os.path.normpath(PNG))


if __name__ == "__main__":
    main(sys.argv[1:])
