"""The seed paper's Figure 6 benchmark: a static scene of 27 cubes (3x3x3, each
8x8x8 cells of 12 tets: 165,888 tets, 33,507 nodes) resting on a floor, time
per step split by phase for the broad-phase cases A (all tets registered),
B (surface tets only), C (B + interior faces skipped) and ours (surface
triangles near other pieces), at 1 and 2 threads.

    /usr/bin/python3.11 scripts/bench/bench_cubes27.py [--steps 20] [--out out/bench]

Writes cubes27.json and cubes27.png (a bar chart like the seed's Figure 6)."""
import argparse
import json
import os
import time

import numpy as np

import qdem
from qdem import _core

from benchutil import floorAndGravity

CASES = [("A", 1), ("B", 2), ("C", 3), ("ours", 0)]
PHASES = ["broadPhase", "pointPolygon", "edgeEdge", "elements", "integrate", "obstacles"]


def scene(L=4.0, mat=None):
    """27 cubes of edge L, Table 1 material, in contact with each other and a
    floor wall.  L = 4 m is the smallest round size at which Table 1's time
    step (6.4e-6 s) is stable for 8x8x8-cell cubes (the viscous limit grows as
    the element size squared; see doc/formulation.md)."""
    mat = mat or qdem.QdemMat()   # seed Table 1: E 5e8, nu 0.4, rho 700, eta 2.5e5, r 0.04
    r = mat.radius
    w = qdem.World()
    cube = qdem.boxMesh((L, L, L), (8, 8, 8), tetsPerCell=12)
    gap = 2 * r - 0.002               # neighbouring cubes overlap slightly: every face in contact
    for i in range(3):
        for j in range(3):
            for k in range(3):
                w.addPiece(cube, mat, pos=(i * (L + gap), j * (L + gap), L / 2 + r - 0.001 + k * (L + gap)))
    floorAndGravity(w)
    return w


def measure(w, steps, case, threads):
    _core.setThreads(threads)
    w.core.broadPhase = case
    dt = min(6.4e-6, w.stableDt()["combined"])   # Table 1's step
    w.core.step(dt, 3)
    acc = dict.fromkeys(PHASES, 0.0)
    rebuilds0 = w.core.verletRebuilds
    t0 = time.perf_counter()
    for _ in range(steps):
        w.core.step(dt, 1)
        for k, v in w.core.timings.items():
            acc[k] = acc.get(k, 0.0) + v
    wall = (time.perf_counter() - t0) / steps
    ms = {k: 1e3 * v / steps for k, v in acc.items()}
    contact = ms["broadPhase"] + ms["pointPolygon"] + ms["edgeEdge"]
    return dict(ms, contact_ms=contact, step_ms=1e3 * wall, ns_per_tet_step=1e9 * wall / w.core.nTets,
                pointPolygonContacts=w.core.contactCounts["pointPolygon"],
                edgeEdgeContacts=w.core.contactCounts["edgeEdge"],
                interiorFaceTests=w.core.contactCounts["interiorFaceTests"],
                verletRebuilds=w.core.verletRebuilds - rebuilds0)


def rebuildCost(w, threads=2, n=3):
    """Time of a step that rebuilds the Verlet lists (forced by nudging the
    skin), against an ordinary step."""
    _core.setThreads(threads)
    w.core.broadPhase = 0
    dt = min(6.4e-6, w.stableDt()["combined"])
    w.core.step(dt, 2)
    skin0, with_, without = w.core.verletSkin, 0.0, 0.0
    for i in range(n):
        w.core.verletSkin = skin0 * (1.01 + 0.01 * (i % 2))
        t = time.perf_counter()
        w.core.step(dt, 1)
        with_ += time.perf_counter() - t
        t = time.perf_counter()
        w.core.step(dt, 1)
        without += time.perf_counter() - t
    w.core.verletSkin = skin0
    return {"rebuild_step_ms": 1e3 * with_ / n, "ordinary_step_ms": 1e3 * without / n}


def chart(res, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(res), figsize=(5 * len(res), 4.5), sharey=True)
    axes = np.atleast_1d(axes)
    colors = dict(broadPhase="#4c72b0", pointPolygon="#dd8452", edgeEdge="#55a868", elements="#c44e52",
                  integrate="#8172b3", obstacles="#937860")
    for ax, (th, cases) in zip(axes, sorted(res.items())):
        names = [c for c, _ in CASES]
        bottom = np.zeros(len(names))
        for ph in PHASES:
            v = np.array([cases[c][ph] for c in names])
            ax.bar(names, v, bottom=bottom, label=ph, color=colors[ph])
            bottom += v
        ax.set_title("%s thread%s" % (th, "s" if th != "1" else ""))
        ax.set_ylabel("time per step [ms]")
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("27 cubes, 165,888 tets: time per step by phase (seed Figure 6 cases A/B/C and ours)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--out", default="out/bench")
    ap.add_argument("--size", type=float, default=4.0, help="cube edge [m]")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    w = scene(a.size)
    print("cubes27: %d tets, %d nodes; stable dt %s" % (w.core.nTets, w.core.nNodes, w.stableDt()))
    _core.setThreads(2)
    w.core.step(min(6.4e-6, w.stableDt()["combined"]), 20)   # let every contact form
    res = {}
    for threads in (1, 2):
        res[str(threads)] = {}
        for name, case in CASES:
            res[str(threads)][name] = measure(w, a.steps, case, threads)
            r = res[str(threads)][name]
            print("  %d thread(s) case %-4s: step %.2f ms (%.1f ns/tet), contact %.2f ms [broad %.2f, "
                  "point-polygon %.2f, edge-edge %.2f], elements %.2f ms"
                  % (threads, name, r["step_ms"], r["ns_per_tet_step"], r["contact_ms"], r["broadPhase"],
                     r["pointPolygon"], r["edgeEdge"], r["elements"]), flush=True)
    rebuild = rebuildCost(w)
    print("  Verlet rebuild: %.2f ms per step with a rebuild, %.2f without" % (rebuild["rebuild_step_ms"],
                                                                             rebuild["ordinary_step_ms"]))
    _core.setThreads(2)
    two = res["2"]
    out = {"tets": w.core.nTets, "nodes": w.core.nNodes, "cube_edge_m": a.size, "dt": min(6.4e-6, w.stableDt()["combined"]),
           "stable_dt": w.stableDt(), "threads": res, "verlet_rebuild_2_threads": rebuild,
           "contact_A_over_C_2_threads": two["A"]["contact_ms"] / two["C"]["contact_ms"],
           "contact_A_over_ours_2_threads": two["A"]["contact_ms"] / two["ours"]["contact_ms"],
           "targets": {"contact_A_over_C": 5.0, "case_C_ns_per_tet_step": 30.0}}
    with open(os.path.join(a.out, "cubes27.json"), "w") as f:
        json.dump(out, f, indent=2)
    chart(res, os.path.join(a.out, "cubes27.png"))
    print(json.dumps({k: v for k, v in out.items() if k != "threads"}, indent=2))


if __name__ == "__main__":
    main()
