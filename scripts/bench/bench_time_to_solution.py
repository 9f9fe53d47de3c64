"""Time to solution of the seed's shogi scenes (doc/performance.md, "Time to
solution"): wall and CPU seconds per simulated second of each scene at 766
times real size and at real size, on 2 threads, with each "lever" (a set of
core settings: the implicit viscous solve's preconditioner today) timed
over the same steps, interleaved; and the whole runs' wall time, measured
where a kept log of a whole run exists, projected otherwise.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 \
        scripts/bench/bench_time_to_solution.py [--steps 200] [--rounds 3] [--threads 2] \
        [--scenes two_rooks,king_and_pawns,forty_front] [--scales 766,1] [--levers jacobi,cholesky] \
        [--out out/bench] [--log bench/logs/time_to_solution_<date>.json]

The scenes (Table 1's material, the particle radius scaled with the pieces,
0.04 m at 766x; bare core world, the floor as stiff as the pieces, gravity;
implicit viscosity at 0.8 of its stable step, warm-started; friction 0.1):

* two_rooks, king_and_pawns: built as qdem.scenes.shogi builds them (the
  first piece tipped) and stepped --warmup steps (the first steps' sag under
  sudden gravity, dearer than the rest) before the timed window.
* forty_front: the forty-piece line from a checkpoint at its front, made as
  scripts/shogi/time_to_solution_baseline.py makes it: the king placed
  3e-4 m x scale from the rook, turned as a rigid body with the angular
  velocity of its fall, stepped until the rook is hit and --after steps
  more; pieces 3-40 held (dynamic = False: what sleeping pieces ahead of
  the front cost).  The checkpoint is kept in --checkpoints and made once.

Each lever (LEVERS: core attribute -> value) is timed `--rounds` times over
the same `--steps` steps (the state reloaded before each round), the levers
interleaved within a round; wall and CPU time, CG iterations per step, the
core's phase timers, the load average before and after and the other
processes' CPU during the run (benchutil.LoadProbe).  A lever whose
attributes this build lacks is recorded as not available, not timed.

Full runs (--refresh-full-runs JSON: only these, into a JSON already written):
bench/logs/time_to_solution_full_<name>.json (written by
scripts/shogi/time_to_solution_full.py: a scene at real size run to its
end) are copied into "full_runs"; the forty-piece line at real size, never
run whole, gets wall_s null, status "not run" and a projected wall time
(PROJECTION below: the measured cost per simulated second at the front
times the line's duration at real size, Froude-scaled from the 766x runs,
times the pieces awake in those runs over those at the checkpoint).
"""
import argparse
import glob
import json
import math
import os
import platform
import shutil
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "shogi"))

import qdem  # noqa: E402
from qdem import _core  # noqa: E402
from qdem.scenes import shogi  # noqa: E402
from benchutil import BUSY_RULE, floorAndGravity, timedWindow  # noqa: E402

G = 9.80665
DT_FACTOR = 0.8            # as domino.py's dtFactor
TABLE1_SCALE = 766         # scales.table1Scale(): Table 1 stable at 6.4e-6 s explicitly (doc/shogi.md)
HELD_FROM = 2              # forty_front: pieces from this index on held
FRICTION = 0.1

# The settings compared.  "old" and "new" name the reference and the
# default; a later lever (adaptive rigidity, mixed precision, ...) is one
# more row here (its core attributes), and "all" the levers together.
LEVERS = {
    "jacobi": {"viscousPreconditioner": 0},
    "cholesky": {"viscousPreconditioner": 1},
}
OLD, NEW = "jacobi", "cholesky"

# name -> (qdem.scenes.shogi scene, from a front checkpoint)
SCENES = {"two_rooks": ("two_rooks", False), "king_and_pawns": ("king_pawns", False),
          "forty_front": ("forty", True)}

# Simulated time of each scene to its end at real size [s], friction 0.1
# unless named (at scale s: t sqrt(s), Froude): where it comes from.
DURATION = {
    "two_rooks": (0.1268, "the second rook fallen (70 % height) in the real-size Table 1 run, friction 0.1 "
                          "(doc/shogi.md, 'Toward real size')"),
    "king_and_pawns": (0.122, "the second pawn fallen in the real-size run of the soft material "
                              "(doc/shogi.md, 'King and two pawns'; Table 1's not run to its end)"),
    "forty_front": (59.57 / math.sqrt(TABLE1_SCALE),
                    "all 40 fallen at 59.57 s in the 766x Table 1 run, friction 0.1, Froude-scaled by "
                    "1/sqrt(766) (doc/shogi.md, 'Results')"),
}
FORTY_FULL = {  # full-run name -> (simulated time at real size, where from)
    "forty_real_size_mu0.1": (59.57 / math.sqrt(TABLE1_SCALE),
                              "all 40 fallen at 59.57 s in the 766x Table 1 run, friction 0.1, / sqrt(766)"),
    "forty_real_size_mu0.5": (62.7 / math.sqrt(TABLE1_SCALE),
                              "21 of 40 hit, the line at rest from 62.7 s in the 766x Table 1 run, friction 0.5, "
                              "/ sqrt(766)"),
}
AWAKE_IN_RUN = 3  # pieces awake at a time in the 766x forty runs, pieces held 3 behind the front (doc/shogi.md)
PROJECTION = ("projected_wall_s = wall s per simulated s at the front (real size, 2 threads, the default lever, "
              "median) x the line's simulated time at real size (the 766x Table 1 run's, / sqrt(766)) x "
              "(%d pieces awake at a time in the 766x runs, pieces held 3 behind the front) / (pieces awake at the "
              "checkpoint); the cost taken as proportional to the pieces awake, the held pieces' own cost "
              "included; the friction-0.5 line costed at the friction-0.1 front's rate" % AWAKE_IN_RUN)


def build(sceneName, scale):
    """A shogi scene in a bare core world: (world, pieces, H of the tallest)."""
    w = qdem.World()
    mat = qdem.QdemMat(frictionPiece=FRICTION, radius=qdem.QdemMat().radius * scale / TABLE1_SCALE)
    pieces = shogi.scene(sceneName, mat, float(scale), world=w)
    floorAndGravity(w, G, young=max(1e7, mat.young))  # the floor as domino.py's
    w.core.viscousIntegration = 1                      # implicit viscosity
    w.core.viscousWarmStart = True
    H = max(shogi.KINDS[k][0] for k in shogi.SCENES[sceneName]["kinds"]) * scale * 1e-3
    return w, pieces, H


def awake(w):
    c = w.core
    return sum(1 for i in range(c.nPieces) if c.dynamic(i) and not c.asleep(i))


def frontCheckpoint(scale, after, path):
    """The forty-piece line at its front (time_to_solution_baseline.py's set-up at `scale`)."""
    import time_to_solution_baseline as baseline
    w, pieces, H = build("forty", scale)
    dt = DT_FACTOR * w.stableDt()["combinedImplicit"]
    # At 766x the king's hit sinks into the rook beyond the contact reach
    # (StabilityError: 0.0802 m against 0.08 m when it falls from its set-up,
    # 13,034 steps; the same at step 282 from this approach): recorded as failed.
    th, omega = baseline.tipTowardRook(pieces, None, 3e-4 * scale, math.sqrt(G / H))
    baseline.hold(pieces, HELD_FROM)
    hitSpeed = 0.02 * math.sqrt(G * H)
    start, steps, hitAt = time.time(), 0, None
    while hitAt is None or steps < hitAt + after:
        w.core.step(dt, 50)
        steps += 50
        if hitAt is None and np.linalg.norm(pieces[1].velocity) > hitSpeed:
            hitAt = steps
        if steps > 200000:
            raise RuntimeError("forty_front at scale %g: the rook was not hit within 200,000 steps: the set-up "
                               "is wrong" % scale)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    qdem.saveState(path, world=w, dt=dt, hit_step=hitAt, steps=steps, wall_s=time.time() - start,
                   king_angle_deg=math.degrees(th), king_omega=omega)
    print("time to solution: forty_front checkpoint at scale %g: rook hit at step %d, %d steps, %.0f s wall -> %s"
          % (scale, hitAt, steps, time.time() - start, path), flush=True)


def prepare(name, scale, a):
    """(world, dt, state, how the timed window starts) for one scene."""
    sceneName, fromFront = SCENES[name]
    if fromFront:
        path = os.path.join(a.checkpoints, "forty_front_x%g_mu%g.npz" % (scale, FRICTION))
        if not os.path.exists(path):
            frontCheckpoint(scale, a.after, path)
        w, pieces, _ = build(sceneName, scale)
        for i, p in enumerate(pieces):
            p.dynamic = i < HELD_FROM
        extra = qdem.loadState(path, world=w)
        dt = float(extra["dt"])
        start = ("checkpoint %s: %d steps past the rook's hit, pieces %d-%d held" % (
            path, int(extra["steps"]) - int(extra["hit_step"]), HELD_FROM + 1, len(pieces)))
    else:
        w, pieces, _ = build(sceneName, scale)
        dt = DT_FACTOR * w.stableDt()["combinedImplicit"]
        w.core.step(dt, a.warmup)
        start = "%d steps from the set-up (the first piece tipped)" % a.warmup
    return w, dt, w.core.saveState(), start


def timeLever(w, dt, state, settings, steps):
    """One timed window with `settings` set on the core: its run record."""
    w.core.loadState(state)
    for k, v in settings.items():
        setattr(w.core, k, v)
    w.core.step(dt, 3)                          # lists, layout and factors built anew after loading
    rec, its, phases = timedWindow(w, dt, steps)
    wall, cpu = rec["wall_s"], rec["cpu_s"]
    total = sum(phases.values()) or 1.0
    rec.update(ms_per_step=1e3 * wall / steps, cpu_ms_per_step=1e3 * cpu / steps,
               wall_s_per_simulated_s=wall / (steps * dt), cpu_s_per_simulated_s=cpu / (steps * dt),
               cg_iterations_per_step=its / steps, pieces_awake=awake(w),
               phase_shares={k: v / total for k, v in sorted(phases.items()) if v > 0})
    return rec


def stat(values):
    v = [x for x in values if x is not None]
    return {"n": len(v), "min": min(v), "median": statistics.median(v), "max": max(v)} if v else None


KEYS = ("wall_s_per_simulated_s", "cpu_s_per_simulated_s", "ms_per_step", "cpu_ms_per_step",
        "cg_iterations_per_step", "pieces_awake", "load1")


def scene(name, scale, a, levers):
    """One scene at one scale, every lever interleaved: its JSON entry.  A
    scene the core stops (StabilityError) is recorded as failed, its figures
    null, with the error's first sentence: never a figure from a broken run."""
    try:
        return measured(name, scale, a, levers)
    except _core.StabilityError as e:
        reason = str(e).split(". ")[0]
        print("time to solution: %s x%g FAILED: %s" % (name, scale, reason), flush=True)
        nulls = {"old": None, "new": None}
        return {"name": name, "scene": SCENES[name][0], "scale": scale, "pieces": len(shogi.SCENES[SCENES[name][0]]
                                                                                       ["kinds"]),
                "status": "failed", "error": reason, "rounds": a.rounds, "levers": {}, "pieces_awake": None,
                "wall_s_per_simulated_s": dict(nulls), "cpu_s_per_simulated_s": dict(nulls),
                "cg_iterations_per_step": dict(nulls), "load1": None,
                "projected_full_run": {"wall_s": None, "simulated_s": DURATION[name][0] * math.sqrt(scale)}}


def measured(name, scale, a, levers):
    w, dt, state, start = prepare(name, scale, a)
    available = {n: s for n, s in levers.items() if all(hasattr(w.core, k) for k in s)}
    runs = {n: [] for n in available}
    for r in range(a.rounds):
        for n, settings in available.items():
            rec = timeLever(w, dt, state, settings, a.steps)
            runs[n].append(rec)
            print("time to solution: %s x%g round %d %-8s: %.3g wall s / simulated s (CPU %.3g), %.2f ms/step, "
                  "%.2f CG its/step, %d awake; load %.2f, others %.2f%s" % (
                      name, scale, r, n, rec["wall_s_per_simulated_s"], rec["cpu_s_per_simulated_s"],
                      rec["ms_per_step"], rec["cg_iterations_per_step"], rec["pieces_awake"], rec["load1"],
                      rec["other_cores"], " BUSY" if rec["busy"] else ""), flush=True)
    entry = {"name": name, "scene": SCENES[name][0], "scale": scale, "pieces": w.core.nPieces, "tets": w.core.nTets,
             "dt": dt,
             "start": start, "steps": a.steps, "rounds": a.rounds, "threads": a.threads,
             "status": "measured", "levers": {}}
    for n in levers:
        if n not in available:
            entry["levers"][n] = {"status": "not available in this build", "settings": levers[n]}
            continue
        rs = runs[n]
        phases = {k: statistics.median(x["phase_shares"].get(k, 0.0) for x in rs)
                  for k in sorted({k for x in rs for k in x["phase_shares"]})}
        entry["levers"][n] = {"settings": levers[n], "summary": {k: stat([x[k] for x in rs]) for k in KEYS},
                              "phase_shares_median": phases, "runs": rs}

    def median(lever, key):
        s = entry["levers"].get(lever, {}).get("summary")
        return s[key]["median"] if s and s.get(key) else None

    for key in ("wall_s_per_simulated_s", "cpu_s_per_simulated_s", "cg_iterations_per_step"):
        entry[key] = {"old": median(OLD, key), "new": median(NEW, key)}
    allLoads = [x["load1"] for rs in runs.values() for x in rs]
    entry["load1"] = {"min": min(allLoads), "median": statistics.median(allLoads)} if allLoads else None
    entry["pieces_awake"] = median(NEW, "pieces_awake")
    t, src = DURATION[name]
    t *= math.sqrt(scale)
    factor = AWAKE_IN_RUN / entry["pieces_awake"] if SCENES[name][1] and entry["pieces_awake"] else 1.0
    new = entry["wall_s_per_simulated_s"]["new"]
    newCpu = entry["cpu_s_per_simulated_s"]["new"]
    entry["projected_full_run"] = {
        "cpu_s": newCpu * t * factor if newCpu is not None else None,
        "simulated_s": t, "simulated_from": src + ("" if scale == 1 else "; x sqrt(%g)" % scale),
        "awake_factor": factor,
        "wall_s": new * t * factor if new is not None else None,
        "how": "projected: the median wall s per simulated s of the default lever x the simulated time%s" % (
            " x %d pieces awake in the 766x runs / %d at the checkpoint" % (AWAKE_IN_RUN, entry["pieces_awake"])
            if factor != 1.0 else "")}
    return entry


def fullRuns(logs, forty):
    """Kept whole-run logs (bench/logs/time_to_solution_full_*.json), and
    the forty-piece line at real size: its log if kept, else projected."""
    out = {}
    for p in sorted(glob.glob(os.path.join(logs, "time_to_solution_full_*.json"))):
        d = json.load(open(p))
        out[d["name"]] = {"wall_s": d["wall_s"], "cpu_s": d.get("cpu_s"), "status": "measured", "log": p,
                          "simulated_s": d.get("simulated_s"), "threads": d.get("threads"),
                          "load1": d.get("load1"), "date": d.get("date"), "ended": d.get("ended")}
    rate = forty["wall_s_per_simulated_s"]["new"] if forty else None
    awakeNow = forty.get("pieces_awake") if forty else None
    for name, (t, src) in FORTY_FULL.items():
        if name in out:
            continue
        proj = rate * t * AWAKE_IN_RUN / awakeNow if rate and awakeNow else None
        cpu = forty["cpu_s_per_simulated_s"]["new"] if forty else None
        projCpu = cpu * t * AWAKE_IN_RUN / awakeNow if cpu and awakeNow else None
        out[name] = {"wall_s": None, "status": "not run", "projected_wall_s": proj, "projected_cpu_s": projCpu,
                     "load1_at_measurement": forty.get("load1") if forty else None, "simulated_s": t,
                     "simulated_from": src, "projected_how": PROJECTION if proj is not None else
                     "not projected: forty_front at real size was not measured in this run"}
    return out


def host():
    import subprocess
    out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    info = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
    return {"model": info.get("Model name", "").strip(), "cpus": int(info.get("CPU(s)", "0").strip() or 0),
            "python": platform.python_version()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--warmup", type=int, default=300, help="two_rooks, king_and_pawns: steps before the window")
    ap.add_argument("--after", type=int, default=1000, help="forty_front: steps past the rook's hit")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--scales", default="766,1")
    ap.add_argument("--levers", default=",".join(LEVERS))
    ap.add_argument("--checkpoints", default="out/bench/time_to_solution")
    ap.add_argument("--logs", default="bench/logs", help="where the kept whole-run logs are")
    ap.add_argument("--out", default="out/bench")
    ap.add_argument("--log", default=None, help="also keep the JSON here (bench/logs/time_to_solution_<date>.json)")
    ap.add_argument("--refresh-full-runs", metavar="JSON", default=None,
                    help="only re-read the kept whole-run logs into this JSON's full_runs (no timing)")
    a = ap.parse_args()
    if a.refresh_full_runs:
        d = json.load(open(a.refresh_full_runs))
        d["full_runs"] = fullRuns(a.logs, d["scenes"].get("forty_front_real_size"))
        with open(a.refresh_full_runs, "w") as f:
            json.dump(d, f, indent=1)
        print("time to solution: full runs of %s: %s" % (a.refresh_full_runs, {
            k: r["status"] for k, r in d["full_runs"].items()}))
        return
    if a.steps < 1 or a.rounds < 1:
        ap.error("--steps and --rounds must be at least 1")
    names = [s for s in a.scenes.split(",") if s]
    unknown = [s for s in names if s not in SCENES] + [v for v in a.levers.split(",") if v not in LEVERS]
    if unknown:
        ap.error("unknown scene or lever %s (scenes: %s; levers: %s)" % (unknown, list(SCENES), list(LEVERS)))
    levers = {n: LEVERS[n] for n in a.levers.split(",")}
    _core.setThreads(a.threads)
    out = {"benchmark": "bench_time_to_solution", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "material": "Table 1 (E 5e8 Pa, nu 0.4, rho 700, viscosity 2.5e5 Pa s), friction 0.1, particle radius "
                       "0.04 m x scale / 766",
           "viscous": "implicit at %g of its stable step, warm-started PCG" % DT_FACTOR,
           "threads": a.threads, "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "(libgomp default)"),
           "old": OLD, "new": NEW, "levers": levers, "busy_rule": BUSY_RULE, "host": host(),
           "statistic": "median over the rounds (all rounds: the machine is shared; load1 and other_cores "
                        "recorded with each run)", "scenes": {}}
    for name in names:
        for scale in (float(s) for s in a.scales.split(",")):
            key = "%s_%s" % (name, "real_size" if scale == 1 else "%gx" % scale)
            out["scenes"][key] = scene(name, scale, a, levers)
    out["full_runs"] = fullRuns(a.logs, out["scenes"].get("forty_front_real_size"))
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "time_to_solution.json")
    with open(path, "w") as f:
        json.dump(out, f, indent=1)
    if a.log:
        os.makedirs(os.path.dirname(a.log) or ".", exist_ok=True)
        shutil.copy(path, a.log)
    for key, e in out["scenes"].items():
        w = e["wall_s_per_simulated_s"]
        print("time to solution: %-26s %2d pieces: wall s / simulated s %s %s / %s %s; load %s" % (
            key, e["pieces"], OLD, "%.3g" % w["old"] if w["old"] else "-", NEW, "%.3g" % w["new"] if w["new"] else "-",
            "%.2f-%.2f" % (e["load1"]["min"], e["load1"]["median"]) if e["load1"] else "-"))
    for name, r in out["full_runs"].items():
        print("time to solution: full run %s: %s" % (name, "%.0f s wall, measured" % r["wall_s"] if r["wall_s"]
                                                      else "not run, projected %s s" % (
                                                          "%.3g" % r["projected_wall_s"] if r.get("projected_wall_s")
                                                          else "-")))
    print("time to solution -> %s" % path)


if __name__ == "__main__":
    main()
