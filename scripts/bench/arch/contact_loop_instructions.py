"""Instructions per step of the node-obstacle and sphere-triangle contact
kernels, old build against new, counted by valgrind's callgrind at one
OpenMP thread (scripts/bench/callgrind_run.py): for a restructuring of the
contact kernels that must not cost (pkg/contact/ContactLoop.hpp).

    /usr/bin/python3.11 scripts/bench/arch/contact_loop_instructions.py --build OLD/python --build NEW/python \
        [--scene floor spheres] [--steps 20] [--out bench/logs/contact_loop_instructions.json]

Scenes (core worlds, no YADE: the sphere states are set once and held):
  floor    9 cubes of edge 1 m (6^3 cells of 12 tets) on a fixed one-sided
           floor (friction 0.5), pressed 1 mm into it and sliding on it at
           up to 0.5 m/s with a spin: every bottom node in a frictional
           contact with its history.
  spheres  one cube of edge 2 m (8^3 cells) on the floor, 144 spheres of
           radius 0.08 m pressed 2 cm into its top face and sliding over it at
           0.3 m/s with a spin (sphere young 1e8, friction 0.4).
Valgrind does not decode AVX-512: build both with `-DQDEM_NATIVE=OFF
-DCMAKE_CXX_FLAGS=-march=haswell` (AVX2 and FMA, as the native build
contracts) into a separate build directory, e.g. build-cg.
Reported per build and scene: instructions inside World::step per step, and
the inclusive instructions of ObstaclePhase::run and SpherePhase::run.
"""
import argparse
import json
import os
import re
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PHASES = ["ObstaclePhase", "SpherePhase", "PieceContactPhase", "ElementPhase", "IntegrationPhase"]


def floorScene(qdem, _core, np, nCubes, edge, cells):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "arch"))
    import scenes
    mat = qdem.QdemMat()
    w = qdem.World()
    cube = qdem.boxMesh((edge,) * 3, (cells,) * 3, tetsPerCell=12)
    rng = np.random.RandomState(5)
    side = int(round(nCubes ** 0.5))
    for i in range(nCubes):
        x, y = (i % side) * (edge + 4 * mat.radius), (i // side) * (edge + 4 * mat.radius)
        v = rng.uniform(-0.5, 0.5, 3)
        v[2] = 0.0
        w.addPiece(cube, mat, pos=(x, y, edge / 2 + mat.radius - 0.001), vel=tuple(v),
                   angVel=(0.0, 0.0, float(rng.uniform(-0.2, 0.2))))
    scenes.floor(w.core, friction=0.5)
    return w, mat


def inner(a):
    """Runs inside valgrind: builds the scene and steps it."""
    import numpy as np
    import qdem
    from qdem import _core
    _core.setThreads(1)
    if a.scene == "floor":
        w, mat = floorScene(qdem, _core, np, 9, 1.0, 6)
    elif a.scene == "spheres":
        edge = 2.0
        w, mat = floorScene(qdem, _core, np, 1, edge, 8)
        n = 12
        R = 0.08
        g = (np.arange(n) + 0.5) / n * (edge - 2 * R) - (edge - 2 * R) / 2
        X, Y = np.meshgrid(g, g)
        pos = np.column_stack([X.ravel(), Y.ravel(), np.full(n * n, edge + mat.radius + R - 0.02)])
        m = len(pos)
        w.core.setSpheres(np.arange(1, m + 1, dtype=np.int32), np.full(m, R), np.full(m, 1e8), np.full(m, 0.5),
                          np.full(m, 0.4), np.full(m, 0.5), np.full(m, 4.0), np.arange(m + 1, dtype=np.int32),
                          np.zeros(m, dtype=np.int32))
        vel = np.tile([0.3, 0.1, 0.0], (m, 1))
        w.core.setSphereStates(pos, vel, np.tile([0.0, 0.0, 1.0], (m, 1)))
    else:
        raise SystemExit("unknown scene " + a.scene)
    dt = 0.5 * w.stableDt()["combined"]
    w.core.step(dt, a.steps)
    print("STEPS %d counts %s" % (a.steps, json.dumps({k: int(v) for k, v in w.core.contactCounts.items()})))


def count(build, a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
    from callgrind_run import annotate
    t0 = time.time()
    stdout, ann, total = annotate(build, __file__, ["--inner", "--scene", a.scene, "--steps", str(a.steps)])
    info = re.search(r"STEPS (\d+) counts (.*)", stdout)
    phases = {}
    for ph in PHASES:
        m = re.search(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+\S*:qdem::" + ph + r"::run\(double\)", ann, re.M)
        if m:
            phases[ph] = int(m.group(1).replace(",", "")) / a.steps
    return dict(build=build, irPerStep=total / a.steps if total else None, phaseIrPerStep=phases,
                counts=json.loads(info.group(2)) if info else None, seconds=time.time() - t0)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--build", action="append", default=[])
    p.add_argument("--scene", nargs="+", default=["floor", "spheres"])
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--out", default=None)
    p.add_argument("--inner", action="store_true")
    a = p.parse_args()
    if a.inner:
        a.scene = a.scene[0]
        inner(a)
        return
    rows = []
    for scene in a.scene:
        runs = []
        for b in a.build:
            sa = argparse.Namespace(scene=scene, steps=a.steps)
            r = count(b, sa)
            runs.append(r)
            print("%-8s %-40s Ir/step %.4g  phases %s  counts %s" % (scene, b, r["irPerStep"],
                  {k: "%.4g" % v for k, v in r["phaseIrPerStep"].items()}, r["counts"]), flush=True)
        row = dict(scene=scene, steps=a.steps, runs=runs)
        if len(runs) == 2:
            row["ratioTotal"] = runs[1]["irPerStep"] / runs[0]["irPerStep"]
            row["ratioPhases"] = {k: runs[1]["phaseIrPerStep"][k] / runs[0]["phaseIrPerStep"][k]
                                  for k in runs[0]["phaseIrPerStep"] if k in runs[1]["phaseIrPerStep"]}
            print("%-8s new/old: total %.4f  %s" % (scene, row["ratioTotal"],
                  {k: "%.4f" % v for k, v in row["ratioPhases"].items()}), flush=True)
        rows.append(row)
    if a.out:
        with open(a.out, "w") as f:
            json.dump(dict(script="scripts/bench/arch/contact_loop_instructions.py", date=time.strftime("%Y-%m-%d %H:%M"),
                           rows=rows), f, indent=1)


if __name__ == "__main__":
    main()
