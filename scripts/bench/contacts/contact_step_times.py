"""Wall time of the 27-cube step with its contact phase split out, old build
against new, interleaved: the moving 27-cube stack of scripts/arch/scenes.py
(Table 1 material, 8^3 cells of 12 tets per cube: 165,888 tets, each cube
thrown with its own velocity and spin, so faces slide and the Verlet lists are
rebuilt every few steps), timed step by step.

    /usr/bin/python3.11 scripts/bench/contacts/contact_step_times.py \
        --build OLD/python --build NEW/python [--threads 1 2] [--rounds 5] \
        [--warm 10] [--steps 60] [--out bench/logs/contacts_step_times_2026-11-24.json]

Each (round, thread count, build) is a fresh process (PYTHONPATH=<build>,
OMP_WAIT_POLICY=passive); within a round the builds run back to back, so a
burst of load on the shared machine hits old and new alike.  Per process:
`--warm` steps untimed, then `--steps` steps one at a time, each timed
(perf_counter around core.step(dt, 1)) with the phases' own timings and
whether it rebuilt the Verlet lists.  The scene rebuilds its lists on its
own only every few hundred steps, so every `--force-every` (5) steps a
rebuild is forced by setting verletSkin to the next double above its value
(or back): the lists are rebuilt whenever the skin changes, and come out
the same.  Reported per build and thread count,
min and median over the rounds of each process's median:
  step_ns_per_tet   all steps (rebuilds included: the amortised cost)
  ordinary_ms       steps without a rebuild
  rebuild_ms        steps with one; rebuild_ratio = rebuild_ms / ordinary_ms
  pointPolygon, broadPhase, edgeEdge (ms, ordinary steps)
and per round the ratios new/old, with /proc/loadavg before and after each
process (a process that began with a 1-minute load above --busy is flagged
busy and left out of the min/median; it stays in the JSON).
"""
import argparse
import json
import math
import os
import statistics as st
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
KEYS = ["pointPolygon", "broadPhase", "edgeEdge", "elements", "integrate", "obstacles"]


def loadavg():
    with open("/proc/loadavg") as f:
        return [float(x) for x in f.read().split()[:3]]


def inner(a):
    sys.path.insert(0, os.path.join(ROOT, "scripts", "arch"))
    from qdem import _core
    import scenes
    _core.setThreads(a.threads)
    w, dt = scenes.cubes27World(a.cells)
    core = w.core
    core.step(dt, a.warm)
    steps = []
    skin = core.verletSkin
    for k in range(a.steps):
        if a.force_every and k % a.force_every == a.force_every - 1:
            # the lists are rebuilt whenever the skin changes: alternate
            # between the skin and the next double above it
            core.verletSkin = math.nextafter(skin, 1.0) if core.verletSkin == skin else skin
        r0 = core.verletRebuilds
        t0 = time.perf_counter()
        core.step(dt, 1)
        wall = time.perf_counter() - t0
        tm = core.timings
        steps.append(dict(ms=1e3 * wall, rebuild=core.verletRebuilds > r0,
                          **{k: 1e3 * tm.get(k, 0.0) for k in KEYS}))
    print(json.dumps(dict(tets=core.nTets, steps=steps)))


def summarise(res):
    steps = res["steps"]
    ordinary = [s for s in steps if not s["rebuild"]]
    rebuild = [s for s in steps if s["rebuild"]]
    med = lambda xs: st.median(xs) if xs else None
    out = dict(step_ns_per_tet=1e6 * st.mean(s["ms"] for s in steps) / res["tets"],
               step_ns_per_tet_median=1e6 * med([s["ms"] for s in steps]) / res["tets"],
               ordinary_ms=med([s["ms"] for s in ordinary]), rebuild_ms=med([s["ms"] for s in rebuild]),
               rebuilds=len(rebuild), steps=len(steps))
    out["rebuild_ratio"] = out["rebuild_ms"] / out["ordinary_ms"] if rebuild and ordinary else None
    for k in KEYS:
        out[k] = med([s[k] for s in ordinary])
        out[k + "_rebuildStep"] = med([s[k] for s in rebuild])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", action="append", default=[])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--cells", type=int, default=8)
    ap.add_argument("--warm", type=int, default=10)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--force-every", type=int, default=5,
                    help="force a Verlet rebuild every this many steps (0: only the scene's own)")
    ap.add_argument("--busy", type=float, default=2.5, help="1-minute load above which a run is flagged")
    ap.add_argument("--out", default=None)
    ap.add_argument("--inner", action="store_true")
    a = ap.parse_args()
    if a.inner:
        a.threads = a.threads[0]
        return inner(a)
    runs = []
    for rnd in range(a.rounds):
        for th in a.threads:
            for b in a.build:
                env = dict(os.environ, PYTHONPATH=os.path.abspath(b), OMP_NUM_THREADS=str(th),
                           OMP_WAIT_POLICY="passive")
                l0 = loadavg()
                p = subprocess.run([sys.executable, os.path.abspath(__file__), "--inner", "--threads", str(th),
                                    "--cells", str(a.cells), "--warm", str(a.warm), "--steps", str(a.steps),
                                    "--force-every", str(a.force_every)],
                                   env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                if p.returncode != 0:
                    raise SystemExit(p.stderr[-3000:])
                res = json.loads(p.stdout.strip().splitlines()[-1])
                r = dict(round=rnd, threads=th, build=b, load_before=l0, load_after=loadavg(),
                         busy=l0[0] > a.busy, summary=summarise(res), steps=res["steps"])
                runs.append(r)
                s = r["summary"]
                print("round %d thr %d %-40s %.2f ns/tet  ordinary %.2f ms  rebuild %s ms (x%s, %d)  pp %.2f  broad %.2f  "
                      "ee %.2f  load %.2f%s" % (rnd, th, b[-40:], s["step_ns_per_tet"], s["ordinary_ms"],
                                                 "%.2f" % s["rebuild_ms"] if s["rebuild_ms"] else "-",
                                                 "%.2f" % s["rebuild_ratio"] if s["rebuild_ratio"] else "-",
                                                 s["rebuilds"], s["pointPolygon"], s["broadPhase"], s["edgeEdge"],
                                                 l0[0], " BUSY" if r["busy"] else ""), flush=True)
    table = {}
    for th in a.threads:
        for b in a.build:
            ok = [r["summary"] for r in runs if r["threads"] == th and r["build"] == b and not r["busy"]]
            row = {}
            for k in ["step_ns_per_tet", "ordinary_ms", "rebuild_ms", "rebuild_ratio"] + KEYS:
                xs = [s[k] for s in ok if s[k] is not None]
                row[k] = dict(min=min(xs), median=st.median(xs), n=len(xs)) if xs else None
            table["%d/%s" % (th, b)] = row
        if len(a.build) > 1:
            for b in a.build[1:]:
                ratios = []
                for rnd in range(a.rounds):
                    o = [r for r in runs if r["round"] == rnd and r["threads"] == th and r["build"] == a.build[0]]
                    n = [r for r in runs if r["round"] == rnd and r["threads"] == th and r["build"] == b]
                    if o and n and not o[0]["busy"] and not n[0]["busy"]:
                        ratios.append(n[0]["summary"]["step_ns_per_tet"] / o[0]["summary"]["step_ns_per_tet"])
                table["%d/%s/ratio_vs_first" % (th, b)] = dict(
                    median=st.median(ratios) if ratios else None, all=ratios)
    for k, v in table.items():
        print(k, json.dumps(v))
    if a.out:
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        with open(a.out, "w") as f:
            json.dump(dict(scene="cubes27 moving (scripts/arch/scenes.py cubes27World)", cells=a.cells, warm=a.warm,
                           steps=a.steps, force_every=a.force_every, table=table, runs=runs), f, indent=1)


if __name__ == "__main__":
    main()
