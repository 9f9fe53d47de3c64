"""Benchmark (issue 5): 20,000 YADE spheres settling around one QDEM block.

Two runs in one process, same spheres, same engines:
  near - the spheres fill a box around and above the block and settle onto it;
  far  - the same box of spheres, with the block 10 m above it (the
         container's walls are infinite planes: a block beside the container
         would stand behind one of them, and is refused).
For each: YADE's own step time (every engine but QdemEngine, from O.timingEnabled)
and the time QdemEngine spends on sphere coupling (lists, states, sphere-surface
contacts, forces back), and their ratio.  Targets: near <= 25 %, far <= 2 %.
Writes out/bench/spheres.json.

    yade -j 2 -n -x scripts/bench/bench_spheres.py [--spheres 20000] [--steps 600] [--out out/bench]
"""
import argparse
import json
import os
import sys
import time

import numpy as np
import qdem
from yade import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                  Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                  Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, O, pack, utils)

BLOCK = 0.12      # block edge [m]
BOX = 0.36        # container width [m]


def build(nSpheres, far):
    """Container of spheres with the block in its middle (or 10 m above it)."""
    O.reset()
    qdem.reset()
    mat = qdem.QdemMat(young=5e5, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.002, frictionPiece=0.5)
    lift = 10.0 if far else 0.0
    qdem.addPiece(qdem.boxMesh((BLOCK, BLOCK, BLOCK), (8, 8, 8)), mat,
                  pos=(0, 0, BLOCK / 2 + mat.radius + lift))
    wm = O.materials.append(FrictMat(young=1e7, frictionAngle=0.3, density=1000))
    O.bodies.append(utils.wall(0, axis=2, sense=1, material=wm))
    for ax in (0, 1):
        O.bodies.append(utils.wall(-BOX / 2, axis=ax, sense=1, material=wm))
        O.bodies.append(utils.wall(BOX / 2, axis=ax, sense=-1, material=wm))
    sm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.4, density=2500))
    sp = pack.SpherePack()
    r = 0.004
    # A loose cloud filling the box; spheres where the block stands are dropped.
    sp.makeCloud((-BOX / 2, -BOX / 2, 0.001), (BOX / 2, BOX / 2, 0.5), rMean=r, rRelFuzz=0.15,
                 num=int(nSpheres * 1.25), seed=7)
    keep = pack.SpherePack()
    h = BLOCK / 2 + 0.003
    for c, rad in sp:
        if not far and abs(c[0]) < h + rad and abs(c[1]) < h + rad and c[2] < BLOCK + 0.007 + rad:
            continue
        keep.add(c, rad)
        if len(keep) == nSpheres:
            break
    keep.toSimulation(material=sm)
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
                 qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.3)]
    O.dt = min(0.5 * utils.PWaveTimeStep(), 0.5 * O.engines[3].stableDt()["combined"])
    return len(keep)


def measure(steps, warm):
    qe = O.engines[3]
    O.run(warm, True)
    O.timingEnabled = True
    for e in O.engines:
        e.execTime = 0
    c0 = qe.sphereCouplingTime()
    t0 = time.perf_counter()
    O.run(steps, True)
    wall = time.perf_counter() - t0
    yadeOwn = sum(e.execTime for e in O.engines if e is not qe) * 1e-9
    qdemAll = qe.execTime * 1e-9
    coupling = qe.sphereCouplingTime() - c0
    O.timingEnabled = False
    core = qe.world.core
    return {"yade_ms_per_step": 1e3 * yadeOwn / steps, "coupling_ms_per_step": 1e3 * coupling / steps,
            "qdem_engine_ms_per_step": 1e3 * qdemAll / steps, "wall_ms_per_step": 1e3 * wall / steps,
            "coupling_fraction": coupling / yadeOwn,
            "spheres_listed": int(core.nSpheres), "sphere_contacts": int(core.contactCounts["sphere"]),
            "list_refreshes": int(qe._spheres.refreshes) if qe._spheres else 0}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spheres", type=int, default=20000)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--warm", type=int, default=5000, help="steps before measuring (spheres reach the block)")
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args(sys.argv[1:])
    res = {"benchmark": "bench_spheres", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "spheres": None, "threads": qdem._core.getThreads()}
    for name, far in (("near", False), ("far", True)):
        n = build(a.spheres, far)
        res["spheres"] = n
        r = measure(a.steps, a.warm)
        res[name] = r
        res["coupling_fraction_" + name] = r["coupling_fraction"]
        print("bench spheres %s: %d spheres, YADE %.2f ms/step, coupling %.3f ms/step (%.1f %%), %d listed, "
              "%d contacts" % (name, n, r["yade_ms_per_step"], r["coupling_ms_per_step"],
                               100 * r["coupling_fraction"], r["spheres_listed"], r["sphere_contacts"]), flush=True)
    res["per_listed_sphere_us"] = 1e3 * res["near"]["coupling_ms_per_step"] / max(res["near"]["spheres_listed"], 1)
    res["fixed_cost_ms_per_step"] = res["far"]["coupling_ms_per_step"]
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "spheres.json"), "w") as f:
        json.dump(res, f, indent=1)
    print(json.dumps(res, indent=1))


main()
