"""One damped mode x'' + 2 xi w x' + w^2 x = 0 under the two viscous
integrations of QDEM's leapfrog (doc/formulation.md 2.1): explicit (dashpot
on v_{n-1/2}) and implicit (on v_{n+1/2}).  Prints and writes
bench/logs/implicit_one_mode.json:

* the numerical decay rate over xi*w (characteristic roots) for a few
  (xi, w dt): first order, -xi w dt implicit, +xi w dt explicit;
* the stable w dt of each (largest w dt with |z| <= 1, by bisection) against
  the closed forms 2(sqrt(1+xi^2) -+ xi);
* the energy ledger's residual (K at the integer level + U + booked
  dissipation, relative to the start) after a free decay from rest, for the
  implicit force booked against v_{n+1/2} (what QDEM does), v_n and v_{n-1/2}.

Run: /usr/bin/python3.11 scripts/accuracy/implicit_one_mode.py"""
import json
import math
import os
import sys

import numpy as np


def roots(xi, wdt, implicit):
    a, b = wdt, 2 * xi * wdt
    return np.roots([1 + b, a * a - 2 - b, 1]) if implicit else np.roots([1, a * a + b - 2, 1 - b])


def decayRatio(xi, wdt, implicit):
    z = roots(xi, wdt, implicit)
    return float(-np.log(np.abs(z).max()) / wdt / xi)


def stableWdt(xi, implicit):
    lo, hi = 0.0, 100.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        (lo, hi) = (mid, hi) if np.abs(roots(xi, mid, implicit)).max() <= 1 + 1e-12 else (lo, mid)
    return lo


def ledger(xi, wdt, booking, periods=8):
    w, m = 1.0, 1.0
    k, c, dt = w * w, 2 * xi * w, wdt / w
    x, v, D, L0 = 1e-3, 0.0, 0.0, None
    for _ in range(int(periods * 2 * math.pi / dt)):
        f = -k * x - c * v                      # explicit force, viscosity at v_{n-1/2}
        dl = dt * f / (m + dt * c)              # (m + dt c) dv = dt f
        q = c * dl
        vn = v + dt * (f - q) / m
        g = c * v + q                           # the applied viscous force is -g
        D += dt * g * {"vNew": vn, "vMid": 0.5 * (v + vn), "vOld": v}[booking]
        L = 0.5 * k * x * x + 0.5 * m * (0.5 * (v + vn)) ** 2 + D
        L0 = L if L0 is None else L0
        x += dt * vn
        v = vn
    return (L - L0) / L0


def main():
    out = {"decay": [], "stable": [], "ledger": []}
    for xi in (0.05, 0.3, 0.7):  # underdamped: the envelope decays at xi w
        for wdt in (0.01, 0.05, 0.1, 0.2):
            out["decay"].append({"xi": xi, "wdt": wdt, "implicit": decayRatio(xi, wdt, True),
                                 "explicit": decayRatio(xi, wdt, False)})
    for xi in (0.0, 0.3, 1.0, 3.0, 10.0):
        out["stable"].append({"xi": xi, "implicit": stableWdt(xi, True), "explicit": stableWdt(xi, False),
                              "implicitFormula": 2 * (math.sqrt(1 + xi * xi) + xi),
                              "explicitFormula": 2 * (math.sqrt(1 + xi * xi) - xi)})
    for wdt in (0.1, 0.05, 0.025):
        out["ledger"].append({"xi": 0.3, "wdt": wdt, **{b: ledger(0.3, wdt, b) for b in ("vNew", "vMid", "vOld")}})
    for k, rows in out.items():
        print(k)
        for r in rows:
            print("  " + "  ".join("%s=%.4g" % (a, b) for a, b in r.items()))
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "../../bench/logs/implicit_one_mode.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
