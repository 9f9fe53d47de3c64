"""Uniaxial-strain response of the two material laws (doc/formulation.md,
"Material laws"): nominal stress P11 and energy density against the stretch
s of F = diag(s, 1, 1), from full inversion (s = -1) to tension (s = 2),
for Young's modulus E and Poisson's ratio nu.  Writes doc/img/law_uniaxial.png.

    /usr/bin/python3.11 scripts/law_curves.py [nu=0.3]

The formulas are those of pkg/element/laws/*.hpp, written out again here for
this diagonal F: SVK  P11 = (lambda + 2 mu) s (s^2 - 1)/2;
SNH  P11 = mu' (1 - 1/(s^2 + 3)) s + lambda' (s - alpha)."""
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

nu = float(sys.argv[1]) if len(sys.argv) > 1 else 0.3
E = 1.0
lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
muS, lamS = 4 * mu / 3, lam + 5 * mu / 6
alpha = 1 + 0.75 * muS / lamS

s = np.linspace(-1.0, 2.0, 601)
svkP = (lam + 2 * mu) * s * (s ** 2 - 1) / 2
svkW = (lam + 2 * mu) / 2 * ((s ** 2 - 1) / 2) ** 2
Ic = s ** 2 + 2
snhP = muS * (1 - 1 / (Ic + 1)) * s + lamS * (s - alpha)
snhW = muS / 2 * (Ic - 3) + lamS / 2 * ((s - alpha) ** 2 - (1 - alpha) ** 2) - muS / 2 * np.log((Ic + 1) / 4)
hooke = (lam + 2 * mu) * (s - 1)

fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
a1.plot(s, hooke / E, ":", color="gray", label="Hooke (small strain)")
a1.plot(s, svkP / E, label="Saint-Venant-Kirchhoff")
a1.plot(s, snhP / E, label="Stable Neo-Hookean (default)")
sc = 1 / np.sqrt(3)
a1.plot([sc], [(lam + 2 * mu) * sc * (sc ** 2 - 1) / 2 / E], "o", color="C0")
a1.annotate("SVK limit point\ns = 1/sqrt(3)", (sc, (lam + 2 * mu) * sc * (sc ** 2 - 1) / 2 / E),
            (0.9, -2.2), arrowprops=dict(arrowstyle="->"))
a1.axhline(0, color="k", lw=0.5)
a1.axvline(0, color="k", lw=0.5)
a1.set_ylim(-4, 3)
a1.set_xlabel("stretch s  (F = diag(s, 1, 1); s < 0: inverted)")
a1.set_ylabel("nominal stress P11 / E")
a1.set_title("Uniaxial strain, nu = %g" % nu)
a1.legend(loc="upper left")
a2.plot(s, svkW / E, label="Saint-Venant-Kirchhoff")
a2.plot(s, snhW / E, label="Stable Neo-Hookean (default)")
a2.axvline(0, color="k", lw=0.5)
a2.set_ylim(0, 3)
a2.set_xlabel("stretch s")
a2.set_ylabel("energy density W / E")
a2.set_title("SVK: zero energy at the mirror state s = -1")
a2.legend(loc="upper right")
fig.tight_layout()
out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "doc", "img", "law_uniaxial.png")
fig.savefig(out, dpi=110)
print("wrote", os.path.normpath(out))
