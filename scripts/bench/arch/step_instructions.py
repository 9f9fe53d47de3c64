"""Instructions per step, old build against new, counted by valgrind's
callgrind: a figure the shared machine's load cannot move (wall times here
swing 2-10x with other jobs), for comparing builds of the same physics.

    /usr/bin/python3.11 scripts/bench/arch/step_instructions.py --build OLD/python --build NEW/python \
        [--scene cubes27] [--cells 8] [--steps 12] [--out bench/logs/arch_instructions.json]

Each build runs the scene in a fresh process under
`valgrind --tool=callgrind --toggle-collect=<World::step>` at one OpenMP
thread: only the instructions executed inside World::step (and what it calls)
are counted, not Python's or the set-up's.  Scenes:
  cubes27  scripts/arch/scenes.py's thrown 27-cube stack (Table 1 material,
           `--cells`^3 cells of 12 tets per cube: 8 gives the bench's 165,888
           tets), `--steps` steps from the start: Verlet rebuilds included.
Per phase (inclusive instructions of each phase's run()) when the build names
its phases so (qdem::<Name>Phase::run); the total always.  Also reported:
instructions read (Ir) is what valgrind counts; it is not time (cache misses
and stalls are not in it), but an extra reload per iteration or a copied
loop shows up in it one for one.
"""
import argparse
import json
import os
import re
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PHASES = ["ObstaclePhase", "PieceContactPhase", "SpherePhase", "ElementPhase", "IntegrationPhase", "SleepPhase"]


def inner(a):
    """Runs inside valgrind: builds the scene and steps it."""
    sys.path.insert(0, os.path.join(ROOT, "scripts", "arch"))
    from qdem import _core
    _core.setThreads(1)
    if a.scene != "cubes27":
        raise SystemExit("unknown scene " + a.scene)
    import scenes
    w, dt = scenes.cubes27World(a.cells)
    w.core.step(dt, a.steps)
    print("STEPS %d rebuilds %d tets %d" % (a.steps, w.core.verletRebuilds, w.core.nTets))


def count(build, a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
    from callgrind_run import annotate
    t0 = time.time()
    stdout, ann, total = annotate(build, __file__, ["--inner", "--scene", a.scene, "--cells", str(a.cells),
                                                    "--steps", str(a.steps)])
    info = re.search(r"STEPS (\d+) rebuilds (\d+) tets (\d+)", stdout)
    phases = {}
    for ph in PHASES:
        m = re.search(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+\S*:qdem::" + ph + r"::run\(double\)", ann, re.M)
        if m:
            phases[ph] = int(m.group(1).replace(",", ""))
    return dict(build=build, totalIr=total, irPerStep=total / a.steps if total else None,
                phaseIr=phases, rebuilds=int(info.group(2)) if info else None,
                tets=int(info.group(3)) if info else None, seconds=time.time() - t0,
                loadavg=os.getloadavg())


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", action="append", default=[])
    ap.add_argument("--scene", default="cubes27")
    ap.add_argument("--cells", type=int, default=8)
    ap.add_argument("--steps", type=int, default=12)
    ap.add_argument("--out", default=None)
    ap.add_argument("--inner", action="store_true")
    a = ap.parse_args()
    if a.inner:
        return inner(a)
    rows = []
    for b in a.build:
        r = count(os.path.abspath(b), a)
        rows.append(r)
        print("%-45s %14s Ir/step  rebuilds %s  %s" % (b, "{:,.0f}".format(r["irPerStep"]), r["rebuilds"],
              " ".join("%s %.3g" % (k.replace("Phase", ""), v / a.steps) for k, v in r["phaseIr"].items())))
    base = rows[0]["irPerStep"]
    for r in rows[1:]:
        print("%s / %s: %.4f" % (r["build"], rows[0]["build"], r["irPerStep"] / base))
    if a.out:
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        with open(a.out, "w") as f:
            json.dump(dict(scene=a.scene, cells=a.cells, steps=a.steps, threads=1, runs=rows), f, indent=1)


if __name__ == "__main__":
    main()
