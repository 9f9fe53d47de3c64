"""What a QDEM step costs inside YADE beyond the core's own step: the Python
glue (QdemEngine._run: reading the obstacles, gravity and settings from YADE,
handing the reactions back) and YADE's PyRunner call, per step and per
obstacle.

    /usr/bin/python3.11 scripts/bench/bench_glue.py [--rounds 5] [--steps 1500] \\
        [--glue NAME=DIR ...] [--out out/bench/glue.json]

Each --glue names a directory holding a `qdem` package (the .py files; its
_core is the build's, copied in when missing): to compare the glue of two
commits on one core, `git show OLD:py/qdem/X.py` into DIR/qdem/ for every
file.  Default: this build's (build/python) alone.

Scenes (a 3 x 3 x 3-cell block of 135 tets resting on the obstacles, so the
core's step is small and the glue shows): one `utils.wall`, and a
`geom.facetCylinder` of 16 and 64 segments (64 and 256 facets).  Each run is
a fresh `yade -n -x` process (OMP_NUM_THREADS=1): CPU time per step of
`O.run(steps, True)` and of `core.step(dt, steps)` on the same world, the
difference being the glue plus YADE's own engines.  Variants interleave
round after round; the load average and other processes' CPU use are kept
with each run; a run at a load above 1.5 (benchutil.py's rule for one
thread) is flagged busy and left out of the quiet min / median / max, the
figures over all runs written beside them."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

INNER = r"""
import json, sys, time
import qdem
from yade import O, ForceResetter, NewtonIntegrator, utils, geom
segments, steps = int(sys.argv[1]), int(sys.argv[2])
mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=700, radius=0.01, restitution=0.2)
block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), mat, pos=(0, 0, 0.11))
if segments:
    O.bodies.append(geom.facetCylinder((0, 0, 0.5), radius=0.5, height=1.0, segmentsNumber=segments, wallMask=7))
else:
    O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.8 * qe.stableTimeStep()
O.run(100, True)
core = qdem.defaultWorld().core
t0 = time.process_time(); O.run(steps, True); t1 = time.process_time()
t2 = time.process_time(); core.step(O.dt, steps); t3 = time.process_time()
print("GLUE_RESULT " + json.dumps({"obstacles": core.nObstacles, "tets": int(core.nTets),
      "orun_us": 1e6 * (t1 - t0) / steps, "core_us": 1e6 * (t3 - t2) / steps}))
"""


def run(glueDir, segments, steps):
    with tempfile.TemporaryDirectory(prefix="qdem_glue.") as tmp:
        script = os.path.join(tmp, "inner.py")
        with open(script, "w") as f:
            f.write(INNER)
        env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=glueDir)
        t = time.time()
        out = subprocess.run(["timeout", "600", "yade", "-n", "-x", script, str(segments), str(steps)], cwd=tmp,
                             env=env, capture_output=True, text=True)
        wall = time.time() - t
    line = [l for l in out.stdout.splitlines() if l.startswith("GLUE_RESULT ")]
    if not line:
        raise RuntimeError("bench_glue: the run failed:\n" + out.stdout[-2000:] + out.stderr[-2000:])
    r = json.loads(line[0].split(" ", 1)[1])
    r["wall_s"] = wall
    with open("/proc/loadavg") as f:
        r["load1"] = float(f.read().split()[0])
    # (benchutil's rule for a one-thread run: busy when the load is above 1.5)
    r["busy"] = r["load1"] > 1.5
    r["glue_us"] = r["orun_us"] - r["core_us"]
    return r


def summary(values):
    v = sorted(values)
    return {"min": v[0], "median": v[len(v) // 2], "max": v[-1], "n": len(v)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps", type=int, default=1500)
    ap.add_argument("--glue", action="append", default=[], help="NAME=DIR (a directory holding qdem/)")
    ap.add_argument("--segments", default="0,16,64", help="0 = one wall; n = a facet cylinder of n segments")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench", "glue.json"))
    a = ap.parse_args()
    build = os.path.join(ROOT, "build", "python")
    glues = [g.split("=", 1) for g in a.glue] or [["this build", build]]
    so = [f for f in os.listdir(os.path.join(build, "qdem")) if f.startswith("_core")]
    for _, d in glues:  # a glue directory without a core takes the build's
        if not any(f.startswith("_core") for f in os.listdir(os.path.join(d, "qdem"))):
            for f in so:
                shutil.copy(os.path.join(build, "qdem", f), os.path.join(d, "qdem", f))
    segs = [int(s) for s in a.segments.split(",")]
    runs = []
    for rnd in range(a.rounds):
        order = glues if rnd % 2 == 0 else glues[::-1]
        for name, d in order:
            for s in segs:
                r = run(d, s, a.steps)
                r.update(glue=name, segments=s, round=rnd)
                runs.append(r)
                print("round %d %-12s obstacles %4d: O.run %8.1f us/step, core.step %6.1f, glue %8.1f "
                      "(%.2f per obstacle), load %.2f" % (rnd, name, r["obstacles"], r["orun_us"], r["core_us"],
                                                          r["glue_us"], r["glue_us"] / r["obstacles"], r["load1"]),
                      flush=True)
    table = []
    for name, _ in glues:
        for s in segs:
            every = [r for r in runs if r["glue"] == name and r["segments"] == s]
            rs = [r for r in every if not r["busy"]] or every
            table.append({"glue": name, "obstacles": rs[0]["obstacles"], "quiet": len(rs) < len(every) or
                          not every[0]["busy"], "runs": len(every), "quietRuns": sum(not r["busy"] for r in every),
                          "glue_us_all": summary([r["glue_us"] for r in every]),
                          "glue_us": summary([r["glue_us"] for r in rs]),
                          "core_us": summary([r["core_us"] for r in rs]),
                          "orun_us": summary([r["orun_us"] for r in rs]),
                          "load1": summary([r["load1"] for r in rs])})
    print("\nglue per step, CPU us: median (min-max) of the quiet runs (all runs when none was quiet)")
    for t in table:
        g = t["glue_us"]
        print("  %-12s %4d obstacles: %8.1f (%.1f-%.1f), %.2f per obstacle; core.step %.1f; quiet %d/%d; "
              "load %.2f-%.2f" % (t["glue"], t["obstacles"], g["median"], g["min"], g["max"],
                                  g["median"] / t["obstacles"], t["core_us"]["median"], t["quietRuns"], t["runs"],
                                  t["load1"]["min"], t["load1"]["max"]))
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w") as f:
        json.dump({"what": "QDEM step glue inside YADE (scripts/bench/bench_glue.py)", "date": time.strftime(
            "%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "steps": a.steps, "runs": runs, "table": table}, f, indent=1)


if __name__ == "__main__":
    main()
