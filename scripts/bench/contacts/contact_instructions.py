"""Instructions of one 27-cube step, per phase and per contact kernel, old
build against new, counted by valgrind's callgrind (a figure the shared
machine's load cannot move; see scripts/bench/arch/step_instructions.py for
why and what it leaves out: cache misses and stalls are not instructions).

    /usr/bin/python3.11 scripts/bench/contacts/contact_instructions.py \
        --build OLD/python --build NEW/python [--cells 8] [--warm 3] \
        [--out bench/logs/contacts_instructions_2026-11-24.json]

The scene is scripts/arch/scenes.py's moving 27-cube stack (8^3 cells of 12
tets per cube: 165,888 tets), one OpenMP thread.  Per build two processes,
each stepping `--warm` steps and then one more, the measured one:
  ordinary  a step without a Verlet rebuild;
  rebuild   the same step with the lists rebuilt: verletSkin is set to the
            next double above its value before it (the lists are rebuilt
            whenever the skin changes; the lists themselves do not change).
Only the measured step is counted: `--zero-before=qdem::World::step(double)`
zeroes the counters as each step begins, `--toggle-collect` keeps only what
runs inside World::step.  Reported: the step's instructions, and the
inclusive instructions of every function whose name matches one of
FUNCS (phases, the two contact kinds, the list rebuild when the build has it
as its own function)."""
import argparse
import json
import math
import os
import re
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
FUNCS = [r"qdem::World::step\(double\)", r"qdem::\w+Phase::run\(double\)", r"pointPolygon<(true|false)>",
         r"edgeEdge<(true|false)>", r"PieceContactPhase::\w*[Ll]ist\w*\(", r"PieceContactPhase::\w*[Rr]egister\w*\(",
         r"PieceContactPhase::\w*[Tt]riangle\w*\(", r"PieceContactPhase::\w*[Pp]airs?\w*\(", r"GOMP_\w+",
         r"CellGrid::build", r"BoxGrid::build", r"PieceContactPhase::.*_omp_fn"]


def inner(a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "arch"))
    from qdem import _core
    import scenes
    _core.setThreads(1)
    w, dt = scenes.cubes27World(a.cells)
    core = w.core
    core.step(dt, a.warm)
    r0 = core.verletRebuilds
    if a.mode == "rebuild":
        core.verletSkin = math.nextafter(core.verletSkin, 1.0)
    core.step(dt, 1)
    print("TETS %d REBUILT %d" % (core.nTets, core.verletRebuilds - r0))


def count(build, mode, a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "bench"))
    from callgrind_run import annotate
    t0 = time.time()
    stdout, ann, total = annotate(build, __file__, ["--inner", "--mode", mode, "--cells", str(a.cells),
                                                    "--warm", str(a.warm)], zeroBefore=True)
    info = re.search(r"TETS (\d+) REBUILT (\d+)", stdout)
    funcs = {}
    for line in ann.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+\S*?:(.*)$", line)
        if not m:
            continue
        name = m.group(2).split(" [/")[0].strip()
        if any(re.search(f, name) for f in FUNCS):
            funcs[name] = funcs.get(name, 0) + int(m.group(1).replace(",", ""))
    return dict(build=build, mode=mode, stepIr=total, funcIr=funcs, tets=int(info.group(1)) if info else None,
                rebuilt=int(info.group(2)) if info else None, seconds=time.time() - t0, loadavg=os.getloadavg())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", action="append", default=[])
    ap.add_argument("--cells", type=int, default=8)
    ap.add_argument("--warm", type=int, default=3)
    ap.add_argument("--modes", nargs="+", default=["ordinary", "rebuild"])
    ap.add_argument("--mode", default="ordinary")
    ap.add_argument("--out", default=None)
    ap.add_argument("--inner", action="store_true")
    a = ap.parse_args()
    if a.inner:
        return inner(a)
    rows = []
    for b in a.build:
        for mode in a.modes:
            r = count(os.path.abspath(b), mode, a)
            rows.append(r)
            print("%-40s %-9s %14s Ir/step (rebuilt %s)" % (b[-40:], mode, "{:,}".format(r["stepIr"]), r["rebuilt"]))
            for k, v in sorted(r["funcIr"].items(), key=lambda kv: -kv[1]):
                print("    %14s  %s" % ("{:,}".format(v), k[:110]))
            sys.stdout.flush()
    if a.out:
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        with open(a.out, "w") as f:
            json.dump(dict(scene="cubes27 moving (scripts/arch/scenes.py cubes27World)", cells=a.cells,
                           warm=a.warm, threads=1, runs=rows), f, indent=1)


if __name__ == "__main__":
    main()
