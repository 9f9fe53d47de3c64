"""Implicit against explicit viscosity: accuracy and cost from the explicit
(viscous) stable step up to the elastic one (doc/formulation.md 2.1).

Three problems, each with a viscosity that makes the stiffest element mode
heavily damped (xi_max = beta w_max / 2 about 10, so the explicit step is
~1/20 of the elastic one, as Table 1's material at a few cm scale):

* mode    - a free 1 x 0.1 x 0.1 m bar (40 x 4 x 4 cells), released from rest
            in its first bending mode with damping ratio xi = 0.05.  Errors:
            the envelope's decay rate against xi*w, and the energy dissipated
            in the first period against the analytic damped oscillator
            (E(T)/E0 from x(t) = x0 e^(-xi w t)(cos w_d t + xi/sqrt(1-xi^2) sin w_d t)).
* pwave   - a laterally confined bar (1 m, 200 cells) struck at one end at
            v0: the Kelvin-Voigt front spreads as it travels.  Errors against
            the explicit run at half its limit (the reference): front arrival
            (v = v0/2) and rise time (10 % to 90 % of v0) at z = +0.25 m.
* bouncing- a 0.1 m block (3^3 cells) dropped on a floor, as
            bouncing_block.py but viscous.  Errors: the energy ledger's largest
            drift relative to the energy brought in, and the viscous
            dissipation at 0.08 s against the explicit reference.

For every dt: mean CG iterations per step and CPU time per simulated second
(one thread: the wall time on a quiet core; CPU time because the machine is
shared).  Writes out/accuracy/implicit_viscosity.json (and, with --log,
bench/logs/implicit_viscosity.json).

Run: PYTHONPATH=build/python OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/accuracy/implicit_viscosity.py [--short]"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import qdem  # noqa: E402
import qdem.modes as modes  # noqa: E402
from acclib import G, Stepper, floor, lame, oneThread  # noqa: E402

XI_MAX = 10.0  # damping ratio of the stiffest element mode


TOLERANCE = [1e-6]  # viscousTolerance of the implicit runs (the tolerance sweep changes it)


def _setup(w, integration):
    w.core.viscousIntegration = {"explicit": 0, "implicit": 1}[integration]
    w.core.viscousTolerance = TOLERANCE[0]


def _iters(w):
    return w.core.counts.get("viscousIterationsTotal", 0)


# ---- mode: first bending mode of a free bar ----------------------------------
def _barMode():
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.01)
    mesh = qdem.boxMesh((1.0, 0.1, 0.1), (40, 4, 4), tetsPerCell=6)
    lam, mu = modes.lame(mat)
    rows, cols, vals, lumped = modes._stiffness(mesh.nodes, mesh.tets.astype(np.int64), lam, mu)
    n = 3 * len(mesh.nodes)
    minv = 1 / np.sqrt(np.repeat(lumped * mat.density, 3))
    K = sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsc()
    A = sp.diags(minv) @ K @ sp.diags(minv)
    w2, V = sla.eigsh(A, k=10, sigma=-1.0, which="LM")
    order = np.argsort(w2)
    w2, V = w2[order], V[:, order]
    k = int(np.nonzero(w2 > 1e-9 * w2.max())[0][0])
    shape = (minv * V[:, k]).reshape(-1, 3)
    return mat, mesh, math.sqrt(w2[k]), shape / np.abs(shape).max(), lumped * mat.density


def runMode(integration, dtOverElastic, xi=0.05, periods=3, probe=False, _cache={}):
    if "bar" not in _cache:
        _cache["bar"] = _barMode()
    mat0, mesh, omega, shape, mass = _cache["bar"]
    mat = qdem.QdemMat(young=mat0.young, poisson=mat0.poisson, density=mat0.density, radius=mat0.radius,
                       viscosity=lame(mat0.young, mat0.poisson)[1] * 2 * xi / omega)
    w = qdem.World()
    p = w.addPiece(mesh, mat, reorder=False)
    _setup(w, integration)
    a0 = 1e-4
    p.pos[:] = p.refPos + a0 * shape
    w.core.trackEnergy = True
    s = w.stableDt()
    xiMax = mat.viscosity / lame(mat.young, mat.poisson)[1] * (2 / s["elastic"]) / 2
    if probe:  # the explicit limit as a fraction of the elastic one
        return s["combinedExplicit"] / s["elastic"]
    dt = dtOverElastic * s["elastic"]
    if dt > s["combined"]:
        return None
    st = Stepper(w, dt, clock=time.process_time)
    wd = omega * math.sqrt(1 - xi * xi)
    T = 2 * math.pi / wd
    mm = mass[:, None]
    norm = float(np.sum(mm * shape * shape))
    amp, E0, D1 = [], None, None
    nT = int(round(T / dt))
    for i in range(int(periods * T / dt)):
        st(1)
        if E0 is None:
            e = w.core.energy
            E0 = e["kinetic"] + e["elastic"] + e["viscous"]
        if i + 1 == nT:
            D1 = w.core.energy["viscous"]
        amp.append(float(np.sum(mm * shape * (p.pos - p.refPos))) / norm)
    amp = np.abs(np.array(amp))
    half = max(1, int(math.pi / wd / dt))
    peaks = np.array([amp[j * half:(j + 1) * half].max() for j in range(len(amp) // half)])
    t = np.arange(len(peaks)) * math.pi / wd
    rate = -np.polyfit(t[1:], np.log(peaks[1:]), 1)[0]
    tt = nT * dt  # analytic energy left after the simulated first period
    x = math.exp(-xi * omega * tt) * (math.cos(wd * tt) + xi / math.sqrt(1 - xi * xi) * math.sin(wd * tt))
    v = -omega / math.sqrt(1 - xi * xi) * math.exp(-xi * omega * tt) * math.sin(wd * tt)
    dExact = 1 - (x * x + v * v / omega ** 2)
    return dict(rateError=rate / (xi * omega) - 1, dissipated=D1 / E0, dissipatedExact=dExact,
                dissipationError=(D1 / E0) / dExact - 1, xiMax=xiMax, dt=dt, steps=st.steps, wall=st.wall,
                wallPerSecond=st.wall / st.time, cgPerStep=_iters(w) / st.steps, nTets=w.core.nTets)


# ---- pwave: Kelvin-Voigt front in a confined bar ----------------------------
def runPwave(integration, dtOverElastic, cells=200, probe=False, xiMax=XI_MAX, maxSteps=None):
    E, NU, RHO, LZ = 1e7, 0.3, 1000.0, 1.0
    h = LZ / cells
    lam, mu = lame(E, NU)
    w0 = qdem.World()
    m0 = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=0.0, radius=h / 4)
    w0.addPiece(qdem.boxMesh((h, h, LZ), (1, 1, cells)), m0, reorder=False)
    dtEl = w0.stableDt()["elastic"]
    beta = xiMax * dtEl  # xi_max = beta w_max / 2 with w_max = 2 / dtEl
    mat = qdem.QdemMat(young=E, poisson=NU, density=RHO, viscosity=beta * mu, radius=h / 4)
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((h, h, LZ), (1, 1, cells)), mat, reorder=False)
    _setup(w, integration)
    X = p.refPos
    p.blocked[:] = 3
    end = np.isclose(X[:, 2], -LZ / 2)
    v0 = 0.01
    p.blocked[end] = 7
    p.vel[end, 2] = v0
    s = w.stableDt()
    if probe:
        return s["combinedExplicit"] / s["elastic"]
    dt = dtOverElastic * s["elastic"]
    if dt > s["combined"]:
        return None
    c = math.sqrt((lam + 2 * mu) / RHO)
    zs = X[np.argmin(np.abs(X[:, 2] - 0.25)), 2]
    idx = np.where(np.isclose(X[:, 2], zs))[0]
    st = Stepper(w, dt, clock=time.process_time)
    tEnd = (zs + LZ / 2) / c * 1.6
    ts, vs = [], []
    while st.time < tEnd:
        st(1)
        if maxSteps and st.steps >= maxSteps:  # cost only: per-step wall time
            return dict(dt=dt, steps=st.steps, wall=st.wall, wallPerSecond=st.wall / st.time,
                        cgPerStep=_iters(w) / st.steps, nTets=w.core.nTets, estimated=True)
        ts.append(st.time)
        vs.append(float(p.vel[idx, 2].mean()) / v0)
    ts, vs = np.array(ts), np.array(vs)

    def crossing(level):
        i = int(np.nonzero(vs >= level)[0][0])
        return ts[i] - (ts[i] - ts[i - 1]) * (vs[i] - level) / (vs[i] - vs[i - 1])
    return dict(arrival=crossing(0.5), rise=crossing(0.9) - crossing(0.1), dt=dt, steps=st.steps, wall=st.wall,
                wallPerSecond=st.wall / st.time, cgPerStep=_iters(w) / st.steps, nTets=w.core.nTets,
                travel=(zs + LZ / 2) / c)


# ---- bouncing: viscous block on a floor -------------------------------------
def runBouncing(integration, dtOverLimit, cells=3, probe=False):
    L, V0, DROP = 0.1, 1.0, 0.02
    E, NU = 1e7, 0.3
    lam, mu = lame(E, NU)
    w0 = qdem.World()
    w0.addPiece(qdem.boxMesh((L, L, L), (cells,) * 3), qdem.QdemMat(young=E, poisson=NU, density=1000.0,
                                                                      viscosity=0.0, radius=2e-3))
    beta = XI_MAX * w0.stableDt()["elastic"]
    mat = qdem.QdemMat(young=E, poisson=NU, density=1000.0, viscosity=beta * mu, radius=2e-3, restitution=1.0,
                       frictionWall=0.5)
    w = qdem.World()
    p = w.addPiece(qdem.boxMesh((L, L, L), (cells,) * 3), mat, pos=(0, 0, L / 2 + mat.radius + DROP),
                   vel=(0.2, 0, -V0), angVel=(0, 2.0, 0))
    floor(w)
    w.core.gravity = (0, 0, -G)
    w.core.trackEnergy = True
    _setup(w, integration)
    s = w.stableDt()
    if probe:
        return s["combinedExplicit"] / s["combinedImplicit"]
    dt = dtOverLimit * s["combinedImplicit"]
    if dt > s["combined"]:
        return None
    st = Stepper(w, dt, clock=time.process_time)
    st(1)
    e0 = w.core.energy["total"]
    m = p.totalMass
    scale = 0.5 * m * (V0 ** 2 + 0.2 ** 2) + m * G * DROP
    worst, chunk = 0.0, max(1, int(2e-4 / dt))
    while st.time < 0.08:
        st(chunk)
        worst = max(worst, abs(w.core.energy["total"] - e0))
    return dict(ledgerError=worst / scale, viscous=w.core.energy["viscous"] / scale, dt=dt, steps=st.steps,
                wall=st.wall, wallPerSecond=st.wall / st.time, cgPerStep=_iters(w) / st.steps,
                nTets=w.core.nTets, explicitLimit=s["combinedExplicit"] / s["combinedImplicit"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--short", action="store_true")
    ap.add_argument("--out", default="out/accuracy")
    ap.add_argument("--log", action="store_true", help="also write bench/logs/implicit_viscosity.json")
    ap.add_argument("--tolerance-only", action="store_true",
                    help="only the tolerance sweep, added to an existing out/accuracy/implicit_viscosity.json")
    ap.add_argument("--crossover-only", action="store_true",
                    help="only the xi_max sweep, added to an existing out/accuracy/implicit_viscosity.json")
    a = ap.parse_args(argv)
    oneThread()
    t0 = time.time()
    if a.tolerance_only:
        with open(os.path.join(a.out, "implicit_viscosity.json")) as f:
            out = json.load(f)
        out["tolerance"] = toleranceSweep(out)
        return _write(out, a, t0)
    if a.crossover_only:
        with open(os.path.join(a.out, "implicit_viscosity.json")) as f:
            out = json.load(f)
        out["crossover"] = crossoverSweep()
        return _write(out, a, t0)
    fr = (0.1, 0.3, 0.9) if a.short else (0.05, 0.1, 0.2, 0.4, 0.9)
    out = {"xiMax": XI_MAX, "mode": [], "pwave": [], "bouncing": []}

    def log(name, r):
        print("implicit_viscosity %-8s %s" % (name, "  ".join(
            "%s=%.4g" % (k, v) for k, v in r.items() if isinstance(v, (int, float)))), flush=True)

    # Each problem: explicit just below its limit (and at half of it: the
    # reference), implicit over fractions of the elastic (or combined) limit.
    for name, run in (("mode", runMode), ("pwave", runPwave), ("bouncing", runBouncing)):
        rows = []
        exFrac = run("explicit", 1.0, probe=True)  # the explicit limit / the implicit one
        for f in (0.5 * exFrac, 0.95 * exFrac):
            r = run("explicit", f)
            if r:
                r.update(integration="explicit", fraction=f)
                rows.append(r)
                log(name, r)
        for f in (0.95 * exFrac,) + fr:
            r = run("implicit", f)
            if r:
                r.update(integration="implicit", fraction=f)
                rows.append(r)
                log(name, r)
        ref = rows[0]  # explicit at half its limit
        for r in rows:
            if name == "pwave":
                r["arrivalError"] = r["arrival"] / ref["arrival"] - 1
                r["riseError"] = r["rise"] / ref["rise"] - 1
            if name == "bouncing":
                r["dissipationError"] = r["viscous"] / ref["viscous"] - 1
            if name == "mode":
                r["dissipationVsExplicit"] = r["dissipated"] / ref["dissipated"] - 1
        out[name] = rows
    out["tolerance"] = toleranceSweep(out)
    out["crossover"] = crossoverSweep()
    return _write(out, a, t0)


def crossoverSweep():
    """The P-wave bar for xi_max = beta w_max / 2 from 1 to 1000 (the explicit
    step is about 1/(2 xi_max) of the elastic one): explicit at its limit
    against implicit at 0.9 of the elastic limit, tolerance 1e-6 and 1e-3.
    Explicit runs longer than 30,000 steps are costed from their first 3,000."""
    rows = []
    for xi in (1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0):
        ex = runPwave("explicit", 1.0, xiMax=xi, probe=True)
        need = int(300 / (0.95 * ex))  # steps to the end of the run (~300 at the elastic limit, 200 cells)
        r = runPwave("explicit", 0.95 * ex, xiMax=xi, maxSteps=3000 if need > 30000 else None)
        r.update(xiMax=xi, integration="explicit", fraction=0.95 * ex, tolerance=None)
        rows.append(r)
        ref = r
        for tol in (1e-6, 1e-3):
            TOLERANCE[0] = tol
            q = runPwave("implicit", 0.9, xiMax=xi)
            q.update(xiMax=xi, integration="implicit", fraction=0.9, tolerance=tol,
                     speedup=ref["wallPerSecond"] / q["wallPerSecond"])
            if not ref.get("estimated"):
                q["arrivalError"] = q["arrival"] / ref["arrival"] - 1
                q["riseError"] = q["rise"] / ref["rise"] - 1
            rows.append(q)
        TOLERANCE[0] = 1e-6
        for q in rows[-3:]:
            print("implicit_viscosity crossover %s" % "  ".join(
                "%s=%.4g" % (k, v) for k, v in q.items() if isinstance(v, (int, float))), flush=True)
    return rows


def toleranceSweep(out, fraction=0.4):
    """The bar's mode and the bouncing block at 0.4 of the limit, implicit, for
    viscousTolerance 1e-2 .. 1e-8 (1e-3 the default): what the stopping rule buys."""
    rows = []
    refs = {n: next(r for r in out[n] if r["integration"] == "explicit") for n in ("mode", "bouncing")}
    for tol in (1e-2, 1e-3, 1e-4, 1e-6, 1e-8):
        TOLERANCE[0] = tol
        for name, run in (("mode", runMode), ("bouncing", runBouncing)):
            r = run("implicit", fraction)
            r.update(problem=name, tolerance=tol, fraction=fraction)
            if name == "mode":
                r["dissipationVsExplicit"] = r["dissipated"] / refs[name]["dissipated"] - 1
            else:
                r["dissipationError"] = r["viscous"] / refs[name]["viscous"] - 1
            rows.append(r)
            print("implicit_viscosity tolerance %g %s %s" % (tol, name, "  ".join(
                "%s=%.4g" % (k, v) for k, v in r.items() if isinstance(v, (int, float)))), flush=True)
    TOLERANCE[0] = 1e-6
    return rows


def _write(out, a, t0):
    out["seconds"] = out.get("seconds", 0) + time.time() - t0
    os.makedirs(a.out, exist_ok=True)
    paths = [os.path.join(a.out, "implicit_viscosity.json")]
    if a.log:
        paths.append(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../bench/logs/implicit_viscosity.json"))
    for path in paths:
        with open(path, "w") as f:
            json.dump(out, f, indent=1)
        print("implicit_viscosity: wrote %s (%.0f s)" % (path, time.time() - t0), flush=True)



# ---- the doc/accuracy.md section (report.py appends it) ---------------------
def _pct(x):
    return "%+.3f %%" % (100 * x) if abs(x) < 1e-2 else "%+.2f %%" % (100 * x)


def _shogiSentence():
    """The rook's figures at 766x and real size, from scripts/shogi/scales.py's committed log."""
    import glob
    logs = sorted(glob.glob(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench", "logs",
                                         "shogi_scales_*.json")))
    if not logs:
        return ""
    with open(logs[-1]) as f:
        sc = json.load(f)["scales"]
    if "766" not in sc or "1" not in sc:
        return ""
    text = ("  Measured on the shogi rook's mesh (doc/shogi.md, \"Toward real size\"; `scripts/shogi/scales.py`): "
            "the first mode's damping ratio is %.2g at 766x real size and %.3g at real size, where implicit costs "
            "1/%.2g and 1/%.3g of explicit per simulated second in short runs from rest" % (
                sc["766"]["first_mode_damping_ratio"], sc["1"]["first_mode_damping_ratio"],
                sc["766"]["explicit_over_implicit"], sc["1"]["explicit_over_implicit"]))
    runs = sorted(glob.glob(os.path.join(os.path.dirname(logs[-1]), "shogi_cost_in_run_*.json")))
    if runs:  # the cost where the long real-size runs were (scripts/shogi/cost_in_run.py)
        with open(runs[-1]) as f:
            ms = [r["warm"]["cpu_ms_per_step"] / r["dt"] * 1e-3 for r in json.load(f)["runs"].values()
                  if r["scale"] == 1]
        if ms:
            text += ", and 1/%.0f in the long runs (`scripts/shogi/cost_in_run.py`)" % (
                sc["1"]["explicit"]["cpu_s_per_simulated_s"] / max(ms))
    return text + "."


def section(data):
    """Markdown for doc/accuracy.md from the JSON this script writes."""
    tol = data.get("tolerance") or []
    its = {(r["problem"], r["tolerance"]): r["cgPerStep"] for r in tol}
    fewer = [its[(p, 1e-6)] / its[(p, 1e-3)] for p in ("mode", "bouncing") if (p, 1e-6) in its and (p, 1e-3) in its]
    t = ["## Implicit viscosity\n",
         "`scripts/accuracy/implicit_viscosity.py` (raw numbers: `out/accuracy/implicit_viscosity.json`, "
         "committed as `bench/logs/implicit_viscosity.json`).  `viscousIntegration='explicit'` against "
         "`'implicit'` (doc/formulation.md 2.1: each step's conjugate gradients start from the last step's "
         "velocity change; tolerance 1e-6 in the first three tables, the default 1e-3 %s: last table) on three "
         "problems whose stiffest element "
         "mode is heavily damped (xi_max ~ %g: the explicit step is 1/20 to 1/30 of the elastic one, as for "
         "Table 1's material with elements of ~15 cm).  dt is given as a fraction of the elastic (undamped) limit, or for "
         "the bouncing block of the combined limit with contacts; the explicit runs stop at their own limit; "
         "the first explicit row (half its limit) is the reference where no analytic answer exists.  CPU time "
         "per simulated second on one thread (the wall time on a quiet core; CPU time because the machine is "
         "shared).\n" % ("takes %.1f-%.1f times fewer iterations for the same results" % (min(fewer), max(fewer))
                          if fewer else "gives the same results", data["xiMax"])]
    heads = {
        "mode": ("First bending mode of a free bar (xi = 0.05), decay and first-period dissipation",
                 [("decay rate vs xi w", "rateError"), ("dissipation vs analytic", "dissipationError"),
                  ("dissipation vs explicit", "dissipationVsExplicit")]),
        "pwave": ("Kelvin-Voigt front in a confined bar, at z = +0.25 m",
                  [("arrival vs reference", "arrivalError"), ("rise time vs reference", "riseError")]),
        "bouncing": ("Viscous block bouncing on a floor (0.08 s)",
                     [("ledger drift / energy in", "ledgerError"), ("dissipation vs reference", "dissipationError")]),
    }
    for name, (title, cols) in heads.items():
        rows = data.get(name) or []
        if not rows:
            continue
        t.append("### %s\n" % title)
        t.append("| integration | dt / limit | steps | %s | CG iterations / step | CPU s / simulated s |" %
                 " | ".join(c[0] for c in cols))
        t.append("| --- | --- | --- | %s | --- | --- |" % " | ".join("---" for _ in cols))
        for r in rows:
            t.append("| %s | %.3g | %d | %s | %.1f | %.3g |" % (
                r["integration"], r["fraction"], r["steps"], " | ".join(
                    (("%.2e" % r[k]) if k == "ledgerError" else _pct(r[k])) for _, k in cols),
                r["cgPerStep"], r["wallPerSecond"]))
        ex = [r for r in rows if r["integration"] == "explicit"]
        im = [r for r in rows if r["integration"] == "implicit"]
        if ex and im:
            best = ex[-1]  # explicit at its limit: the cheapest explicit run
            same = im[0]   # implicit at the same step
            fastest = min(im, key=lambda r: r["wallPerSecond"])
            t.append("\nAt the explicit limit the implicit step costs %.1fx the explicit one (%.1f CG iterations); "
                     "at %.2g of the limit it runs %.1fx faster than explicit at its limit.\n" % (
                         same["wallPerSecond"] / best["wallPerSecond"], same["cgPerStep"], fastest["fraction"],
                         best["wallPerSecond"] / fastest["wallPerSecond"]))
    cross = data.get("crossover") or []
    if cross:
        t.append("### Where implicit pays: the P-wave bar for xi_max from 1 to 1000\n")
        t.append("The explicit step is about 1/(2 xi_max) of the elastic one; explicit at 0.95 of its limit, "
                 "implicit at 0.9 of the elastic limit (explicit runs beyond 30,000 steps are costed from their "
                 "first 3,000 steps: 'est.').  Errors of the implicit front against the explicit one.\n")
        t.append("| xi_max | explicit CPU s / sim. s | implicit tol | CG iterations / step | implicit CPU s / sim. s "
                 "| implicit speed-up | arrival vs explicit | rise time vs explicit |")
        t.append("| --- | --- | --- | --- | --- | --- | --- | --- |")
        ex = None
        for r in cross:
            if r["integration"] == "explicit":
                ex = r
                continue
            t.append("| %g | %.3g%s | %g | %.1f | %.3g | %.1fx | %s | %s |" % (
                r["xiMax"], ex["wallPerSecond"], " (est.)" if ex.get("estimated") else "", r["tolerance"],
                r["cgPerStep"], r["wallPerSecond"], r["speedup"],
                _pct(r["arrivalError"]) if "arrivalError" in r else "-",
                _pct(r["riseError"]) if "riseError" in r else "-"))
        t.append("")
        first, exFrac, ex = {}, {}, None
        for r in cross:
            if r["integration"] == "explicit":
                ex = r
            elif r["speedup"] > 1 and r["tolerance"] not in first:
                first[r["tolerance"]] = r["xiMax"]
                exFrac[r["tolerance"]] = ex["fraction"] / 0.95  # the explicit limit / the elastic one
        t.append("**Crossover, and the default.** Explicit costs one element pass per step at `dt_ex ~ "
                 "dt_el / (2 xi_max)`; implicit costs one element pass plus `n_cg ~ sqrt(kappa)/2 ln(2/tol)` "
                 "applications of `C` per step at `dt_el`, with `kappa ~ 1 + 3.6 xi_max` at 0.9 `dt_el` "
                 "(doc/formulation.md 2.1), so the speed-up grows as `sqrt(xi_max)`.  Measured, implicit is "
                 "the faster from xi_max = %s (tolerance 1e-6) and %s (the default 1e-3) on, i.e. once "
                 "`stableDt()['combinedExplicit']` is below about 1/%s (1e-6) or 1/%s (1e-3) of "
                 "`stableDt()['combinedImplicit']` (timings on a shared machine: +-30 %%); "
                 "below that, and whenever viscosity does not limit the step at all (xi_max < 1, the usual case "
                 "for metre-scale pieces or low viscosity), the explicit step is cheaper and is exactly the "
                 "scheme the rest of this page measured.  So `viscousIntegration='explicit'` stays the default, "
                 "and the stable-step refusal names the implicit option when viscosity is what limits the step.  "
                 "Table 1's material has xi_max ~ beta c_P / h ~ 1.7 m / h (beta = 1.4e-3 s, c_P = 1,240 m/s): "
                 "~1,700 at real size (h ~ 1 mm), where the implicit step is the only practical choice.%s  "
                 "Implicit viscosity also runs under MPI, with the same stopping rule and iteration count on every "
                 "rank (doc/parallel.md).\n" % (
                     "%g" % first[1e-6] if 1e-6 in first else "-", "%g" % first[1e-3] if 1e-3 in first else "-",
                     "%.0f" % (1 / exFrac[1e-6]) if 1e-6 in exFrac else "-",
                     "%.0f" % (1 / exFrac[1e-3]) if 1e-3 in exFrac else "-", _shogiSentence()))
    if tol:
        t.append("### What the stopping rule buys (implicit at %.2g of the limit)\n" % tol[0]["fraction"])
        t.append("| viscousTolerance | problem | CG iterations / step | CPU s / simulated s | error |")
        t.append("| --- | --- | --- | --- | --- |")
        for r in tol:
            err = ("decay rate %s, dissipation vs analytic %s" % (_pct(r["rateError"]), _pct(r["dissipationError"]))
                   if r["problem"] == "mode" else "ledger %.2e, dissipation vs reference %s" % (
                       r["ledgerError"], _pct(r["dissipationError"])))
            t.append("| %g | %s | %.1f | %.3g | %s |" % (r["tolerance"], r["problem"], r["cgPerStep"],
                                                        r["wallPerSecond"], err))
        t.append("")
    return "\n".join(t) + "\n"


if __name__ == "__main__":
    main()
