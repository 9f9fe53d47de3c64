"""Plots and doc/accuracy.md from out/accuracy/accuracy.json (run_accuracy.py
calls this; `python3 report.py out/accuracy` redoes it from a saved JSON)."""
import glob
import json
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
MARKERS = "osD^v<>px*h"


def _knobs(res):
    knobs = {}
    for r in res["rows"]:
        knobs.setdefault(r["knob"], []).append(r)
    return knobs


def plots(out, outdir):
    """One PNG per problem: |error| against step time, one series per knob;
    and a convergence plot (|error| against element size) per problem that has
    an element-size sweep."""
    written = []
    for name, res in out["problems"].items():
        fig, ax = plt.subplots(figsize=(7.5, 4.8))
        for i, (knob, rows) in enumerate(_knobs(res).items()):
            x = [max(r["wall"], 1e-4) for r in rows]
            y = [max(abs(r["error"]), 1e-9) for r in rows]
            ax.plot(x, y, "-" + MARKERS[i % len(MARKERS)], label=knob, alpha=0.8)
            for r, xi, yi in zip(rows, x, y):
                if r["default"]:
                    ax.plot([xi], [yi], "k*", ms=12, mfc="none")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time of the run's steps [s], one thread")
        ax.set_ylabel("|%s|" % res["error"])
        ax.set_title(res["title"] + "  (star: default level)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        fig.tight_layout()
        p = os.path.join(outdir, "accuracy_%s.png" % name)
        fig.savefig(p, dpi=110)
        plt.close(fig)
        written.append(p)
    conv = [(n, res) for n, res in out["problems"].items() if "order" in res]
    if conv:
        fig, ax = plt.subplots(figsize=(7.5, 4.8))
        for i, (name, res) in enumerate(conv):
            rows = [r for r in res["rows"] if r["knob"] == "element size"]
            h0 = max(r["h"] for r in rows)
            ax.plot([r["h"] / h0 for r in rows], [abs(r["error"]) for r in rows], "-" + MARKERS[i],
                    label="%s (order %.2f, finest three %.2f)" % (name, res["order"], res["orderFine"]))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("element size / coarsest element size")
        ax.set_ylabel("|relative error|")
        ax.set_title("Convergence with element size")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        fig.tight_layout()
        p = os.path.join(outdir, "accuracy_convergence.png")
        fig.savefig(p, dpi=110)
        plt.close(fig)
        written.append(p)
    return written


def _fmt(x):
    return "%+.2e" % x if abs(x) < 1e-3 and x != 0 else "%+.4f" % x


def _table(res):
    lines = ["| knob | level | error | step time [s] | steps | tets | |",
             "| --- | --- | ---: | ---: | ---: | ---: | --- |"]
    best = res.get("best", {})
    for knob, rows in _knobs(res).items():
        for r in rows:
            tag = []
            if r["default"]:
                tag.append("default")
            if best.get(knob) == r["label"] and len(rows) > 1:
                tag.append("**best**")
            lines.append("| %s | %s | %s | %.3f | %d | %d | %s |" % (knob, r["label"], _fmt(r["error"]), r["wall"],
                                                                      r["steps"], r["nTets"], ", ".join(tag)))
    return "\n".join(lines)


KEPT = os.path.join(ROOT, "bench", "logs", "accuracy.json")


def writeDoc(out, outdir):
    """doc/accuracy.md and its plots from a full run; the run's JSON is kept
    as bench/logs/accuracy.json, from which the page can be checked
    (tests/python/test_accuracy_page.py) and regenerated."""
    imgdir = os.path.join(ROOT, "doc", "img")
    os.makedirs(imgdir, exist_ok=True)
    for f in os.listdir(outdir):
        if f.startswith("accuracy_") and f.endswith(".png"):
            shutil.copy(os.path.join(outdir, f), os.path.join(imgdir, f))
    with open(KEPT, "w") as f:
        json.dump(out, f, indent=1)
    path = os.path.join(ROOT, "doc", "accuracy.md")
    with open(path, "w") as f:
        f.write(docText(out, outdir))
    return path


def docText(out, outdir):
    """The text of doc/accuracy.md from a full run's JSON; the sections of the
    implicit-viscosity and mass-scaling studies from their JSON in outdir, or
    the kept ones in bench/logs/."""
    P = out["problems"]

    def row(p, knob, prefix):
        for r in P[p]["rows"]:
            if r["knob"] == knob and r["label"].startswith(prefix):
                return r
        raise KeyError((p, knob, prefix))

    def e(p, knob, prefix, pct=True, digits=1):
        v = row(p, knob, prefix)["error"]
        return "%+.*f %%" % (digits, 100 * v) if pct else "%.2g" % v

    def w(p, knob, prefix):
        return "%.2f s" % row(p, knob, prefix)["wall"]

    def spread(p, knob):
        v = [r["error"] for r in P[p]["rows"] if r["knob"] == knob]
        return 100 * (max(v) - min(v))

    finest = [r for r in P["cantilever"]["rows"] if r["knob"] == "element size"][-1]
    hfine = [r for r in P["hertz"]["rows"] if r["knob"] == "element size"][-1]
    hk = [r for r in P["hertz"]["rows"] if r["knob"] == "contact kinds"]
    nk = hk[0]["label"].rsplit("(", 1)[1].rstrip(")")
    def maxEE(p):
        return max(r.get("edgeEdge", 0) for r in P[p]["rows"])

    def bestTable():
        lines = ["| problem | knob | default | best on the error-cost curve |", "| --- | --- | --- | --- |"]
        for name, res in P.items():
            for knob, rows in _knobs(res).items():
                if len(rows) < 2:
                    continue
                d = [r["label"] for r in rows if r["default"]]
                lines.append("| %s | %s | %s | %s |" % (name, knob, d[0] if d else "(user's choice)",
                                                       res["best"][knob]))
        return "\n".join(lines)

    text = f"""# What accuracy costs in time

Generated by `make accuracy` (`scripts/accuracy/run_accuracy.py`, {out['seconds']:.0f} s on one
thread); do not edit by hand — edit `scripts/accuracy/report.py`.  `make bench`
runs the same study in a short form (out/accuracy/ only).  Each problem has a
known answer; each accuracy knob is varied with the others at their defaults,
and the error and the wall time of the steps are measured in the same run.
Time is the wall time of `World.step` on one thread of a shared machine
(repeat runs differ by ~10 %: compare within a column, not across runs).  Threads
are not a knob here: they change the cost, never the result
(`tests/python/test_threads.py`; costs in [performance.md](performance.md)).
Raw numbers: `out/accuracy/accuracy.json`; the run shown here is kept as
`bench/logs/accuracy.json`, and the page is checked against it by `make test`.

## The problems and their reference answers

| problem | reference | source |
| --- | --- | --- |
| cantilever, L/b = 10, clamped, own weight | `delta = w L^4/(8 E I) + w L^2/(2 kappa G A)`, `w = rho g A`, `I = b^4/12`, `kappa = 10(1+nu)/(12+11nu)` | Euler–Bernoulli beam plus Timoshenko's shear term; Cowper's shear coefficient for a square section |
| P-wave in a laterally confined bar | `c_P = sqrt(E(1-nu)/((1+nu)(1-2nu) rho))` | uniaxial strain: exact at every wavelength (the bar speed `sqrt(E/rho)` holds only for wavelengths much longer than the thickness, and a sharp front has them all) |
| two equal spheres pressed together | `F = 4/3 E* sqrt(R*) d^(3/2)`, `1/E* = 2(1-nu^2)/E`, `R* = (R+r)/2` | Hertz (1882); Johnson, *Contact Mechanics*, §4.2 |
| block sliding on a QDEM slab | deceleration `mu g` | Coulomb kinetic friction, normal force = weight |
| block resting on a slope at half the friction angle | no motion (creep speed 0) | Coulomb static friction |
| free elastic block bouncing on a floor | `E_kin + E_strain + E_springs - W_gravity + D_friction = const` | energy balance (the engine's ledger, formulation.md §2) |

Details (set-up, what is measured, why) are in each script's docstring,
repeated at the end of this page.

## Chosen defaults, and why

* **Contact kinds: point–polygon with the edge and vertex regions, plus
  edge–edge (the engine's default).** On the Hertz spheres ({nk}) the seed's
  face-only inside test gives {e('hertz', 'contact kinds', 'point-polygon, face only')}
  against {e('hertz', 'contact kinds', '+ edge and vertex regions')} with the regions, for the same
  time ({w('hertz', 'contact kinds', 'point-polygon, face only')} vs
  {w('hertz', 'contact kinds', '+ edge and vertex regions')}): a node facing a convex faceted
  surface near an edge projects outside both faces and is lost.  Edge–edge
  changes nothing here and on the sliding block (spheres have no feature
  edges; parallel block/slab edges are faded out by design) and costs nothing
  measurable when it finds no feature-edge pairs; it is what carries an
  edge-on contact (`test_crossed_bars_touch_edge_on_without_tunnelling`), so
  it stays on.
* **Friction model: the Cundall–Strack spring (default).** Sliding
  deceleration is `mu g` to {e('sliding', 'friction model', 'spring', digits=3)} with the spring and
  {e('sliding', 'friction model', 'regularized, vReg = 1e-3', digits=3)} with the regularised law, at the same
  cost; but on a slope at half the friction angle the regularised law creeps
  at {e('stick', 'friction model', 'regularized, vReg = 1e-3', False)} m/s (vReg 1e-3 m/s) and
  {e('stick', 'friction model', 'regularized, vReg = 1e-2', False)} m/s (vReg 1e-2 m/s), as
  `vReg tan(theta)/mu` predicts, where the spring holds the block
  ({e('stick', 'friction model', 'spring', False)} m/s).
* **Time step: 0.8 of the stable step.** Errors barely depend on it: the
  P-wave front is slightly *more* accurate near the limit
  ({e('pwave', 'time step', '0.25', digits=2)} at 0.25, {e('pwave', 'time step', '0.99', digits=2)} at 0.99: the
  dispersion of the central-difference scheme shrinks as the Courant number
  nears 1); the Hertz force changes by {spread('hertz', 'time step'):.2f} % of Hertz between 0.3 and 0.9;
  the energy ledger of the bouncing block drifts in proportion to dt
  ({e('bouncing', 'time step', '0.10')} at 0.1, {e('bouncing', 'time step', '0.80')} at 0.8: first order,
  set by the contact onset falling between steps) and stays below 1 %.  The
  cost is inversely proportional to dt, so the largest safe fraction wins;
  0.8 rather than 0.99 leaves room for what the reference-shape stable step
  does not see (strained slivers stiffen, doc/validation.md).
* **Element size: the user's choice, with these orders.** Constant-strain
  tetrahedra lock in bending: the cantilever with one element through the
  thickness is {e('cantilever', 'element size', 'b/1')} off, with
  elements of {finest['label']} still {100 * finest['error']:+.1f} %;
  the fitted order is {P['cantilever']['order']:.2f} over all levels and {P['cantilever']['orderFine']:.2f} over the
  finest three (the asymptotic order of the CST displacement is 2).  The
  P-wave front converges as h^{P['pwave']['order']:.2f} (a sharp front in a
  dispersive discrete medium spreads as (h^2 x)^(1/3): order 2/3), the Hertz
  force as h^{P['hertz']['order']:.2f}, still {100 * hfine['error']:+.1f} % at {hfine['label']}; part of that
  will not vanish with h (the centres' approach includes the spheres' own
  compliance, which Hertz's half-spaces do not have, and the penalty layer
  of contact springs adds its own).
  Cost grows at least as h^-4 (h^-3 elements, h^-1 steps).  For bending-dominated
  pieces use at least 4 elements through the thickness, or accept ~20 %.
* **tetsPerCell of `qdem.boxMesh`: 5 where bending matters.** At equal cells, 5
  tetrahedra per cell are the fewest elements (at a somewhat smaller stable
  step) and, in the cantilever, the most accurate
  ({e('cantilever', 'tetsPerCell', '5')} in {w('cantilever', 'tetsPerCell', '5')} vs
  {e('cantilever', 'tetsPerCell', '6')} in {w('cantilever', 'tetsPerCell', '6')} for 6 and
  {e('cantilever', 'tetsPerCell', '12')} in {w('cantilever', 'tetsPerCell', '12')} for 12); in the P-wave bar and the bouncing block the
  three differ by less than the error itself.  6 stays `boxMesh`'s default for
  its uniform (Kuhn) element shape, which the seed's 12-tet cubes share.
* **Contact radius r = h.** The contact layer is a set of penalty springs
  `kn = E r`; on the Hertz spheres r = 0.5 h gives {e('hertz', 'contact radius', 'r = 0.5')},
  r = h {e('hertz', 'contact radius', 'r = 1 ')}, r = 2 h {e('hertz', 'contact radius', 'r = 2')}
  (stiffer but the contact begins farther from the mesh surface); cost is the
  same.
* **Broad phase: `'triangles'` (default)**: identical forces, cheapest (Hertz
  {nk}: {w('hertz', 'broad phase', 'triangles')} against
  {w('hertz', 'broad phase', 'A')} for the seed's case A).

The "best" mark in the tables is computed: the cheapest level whose |error| is
within 10 % (plus a negligible amount) of the smallest error of its sweep.
Where it differs from the default, the default is kept for the reasons
above (finer meshes and lower loading speeds are the user's trade; 0.99 of
the stable step is too close to the edge; only the bouncing block's energy
ledger asks for small steps, and its drift at 0.8 stays below 1 %).

{bestTable()}

Not knobs here: *threads* change the cost, never the result (1 and 2 threads
agree to rounding, `test_threads.py`); *precision* — the engine is double
precision throughout, as Debian's YADE.

## What the study found in the engine

* Constant-strain tetrahedra in bending are stiff (shear locking): the
  cantilever needs about 8 elements through the thickness to come within
  {100 * abs(finest['error']):.0f} %, and the Kuhn 6-tet cell is the stiffest of the three
  `boxMesh` patterns ({e('cantilever', 'tetsPerCell', '6')} against {e('cantilever', 'tetsPerCell', '5')}
  for 5 tets at the same cells).  Quadratic or enhanced-strain elements are
  the remedy; the seed's QDEM is CST by construction.
* The energy ledger through an impact is first order in dt
  ({e('bouncing', 'time step', '0.10', digits=2)} at 0.1, {e('bouncing', 'time step', '0.50', digits=2)} at 0.5 of the
  stable step), not second: a penalty contact switches on between two
  steps.  Fine for every use so far; a scene that needs the energy better
  than 0.5 % needs a smaller step.
* The seed's face-only inside test (`pointPolygonRegions=False`) loses
  the contacts of nodes that face the other body's convex edges: on faceted
  spheres {e('hertz', 'contact kinds', 'point-polygon, face only')} instead of
  {e('hertz', 'contact kinds', '+ edge and vertex regions')}.
* Edge–edge contacts do not engage on these problems (most edge–edge
  contacts seen, sampled along each run: {maxEE('hertz')} on the spheres, which
  have no feature edges, {maxEE('sliding')} under the sliding block, whose
  edges are parallel to the slab's and faded out), so here edge–edge is pure
  cost, and a negligible one.


![Convergence](img/accuracy_convergence.png)

"""
    for name, res in P.items():
        text += "## %s\n\nError: %s.\n\n%s\n\n![%s](img/accuracy_%s.png)\n\n" % (
            res["title"], res["error"], _table(res), res["title"], name)
        if "order" in res:
            text += "Fitted convergence order (element size): %.2f over all levels, %.2f over the finest three.\n\n" % (
                res["order"], res["orderFine"])
    # The implicit-viscosity study (its own script, run by make accuracy before
    # this one; the committed log when it was not run).
    for iv in (os.path.join(outdir, "implicit_viscosity.json"), os.path.join(ROOT, "bench", "logs",
                                                                             "implicit_viscosity.json")):
        if os.path.exists(iv):
            sys.path.insert(0, HERE)
            import implicit_viscosity
            with open(iv) as f:
                text += implicit_viscosity.section(json.load(f))
            break
    # Selective mass scaling (its own script, run by make accuracy before this
    # one; the committed log when it was not run).
    for ms in (os.path.join(outdir, "mass_scaling.json"), os.path.join(ROOT, "bench", "logs", "mass_scaling.json")):
        if os.path.exists(ms):
            sys.path.insert(0, HERE)
            import mass_scaling
            with open(ms) as f:
                text += mass_scaling.section(json.load(f))
            break
    # Adaptive rigidity on shogi lines (scripts/shogi/rigidify_cost.py; its committed logs).
    rigidLogs = sorted(glob.glob(os.path.join(ROOT, "bench", "logs", "rigidify_*.json")))
    if rigidLogs:
        sys.path.insert(0, os.path.join(ROOT, "scripts", "shogi"))
        import rigidify_cost
        logs = []
        for path in rigidLogs:
            with open(path) as f:
                logs.append(json.load(f))
        # (rigidify_dominoes.py's brick lines have a table of their own in the
        # developers' notebook: their logs carry no shogi scene arguments)
        text += rigidify_cost.section([log for log in logs if "rigid" in log and "deformable" in log
                                       and log.get("benchmark") != "rigidify_dominoes"])
    text += "## Set-ups (the scripts' docstrings)\n\n"
    sys.path.insert(0, HERE)
    import run_accuracy
    seen = set()
    for name in P:
        mod = run_accuracy.PROBLEMS[name][0]
        if mod in seen:
            continue
        seen.add(mod)
        text += "### `scripts/accuracy/%s.py`\n\n```\n%s\n```\n\n" % (mod.__name__, mod.__doc__.strip())
    return text


if __name__ == "__main__":
    outdir = sys.argv[1] if len(sys.argv) > 1 else "out/accuracy"
    with open(os.path.join(outdir, "accuracy.json")) as f:
        data = json.load(f)
    plots(data, outdir)
    if data["mode"] == "full":
        print(writeDoc(data, outdir))
