"""What adaptive rigidity (QdemEngine.rigidify, doc/formulation.md section 6)
gains per step on the seed's shogi scenes at real size (Table 1, implicit
viscosity, 2 threads): bench_time_to_solution.py's scenes and set-up, the
default lever (Cholesky preconditioner) with rigidify off and on, timed
over the same simulated interval, interleaved, several rounds.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_rigidify.py \\
        [--scenes two_rooks,forty_front] [--scales 1] [--prep 6000] [--steps 300] [--rounds 3] \\
        [--rate 1] [--dwell 0.0005] [--wakeStrain 1e-5] [--log bench/logs/rigidify_gain_<date>.json]
    ... scripts/bench/bench_rigidify.py --table bench/logs/rigidify_gain_<date>.json   (its Markdown table)

Each scene starts as bench_time_to_solution.prepare makes it (two_rooks:
--warmup steps from the set-up; forty_front: the checkpoint at the front,
made once).  From there it is run --prep steps twice, rigidify off and on
(a piece must stay slow to deform for rigidTime before it is made rigid:
the window starts where the rigid run has its pieces rigid, and the
deformable run at the same simulated time); each state is kept.  Then
--rounds rounds, each timing --steps steps from each kept state (off, on),
with the load average, the other processes' CPU (benchutil.LoadProbe), the
pieces rigid and the switches in the window.  The JSON holds every round;
the speed-up is off / on of the wall and CPU seconds per step, min and
median over the rounds.
"""
import argparse
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from qdem import _core  # noqa: E402
import bench_time_to_solution as tts  # noqa: E402
from benchutil import timedWindow  # noqa: E402


def settings(a, on):
    return {"viscousPreconditioner": 1, "rigidify": on, "rigidStrainRate": a.rate, "rigidTime": a.dwell,
            "rigidWakeStrain": a.wakeStrain, "rigidWakeLoad": a.wakeLoad}


def window(w, dt, state, s, steps):
    w.core.loadState(state)
    for k, v in s.items():
        setattr(w.core, k, v)
    sw0 = w.core.rigidSwitches
    rec, its, _ = timedWindow(w, dt, steps)
    rec.update(cpu_ms_per_step=1e3 * rec["cpu_s"] / steps, ms_per_step=1e3 * rec["wall_s"] / steps,
               cg_iterations_per_step=its / steps, rigid_at_end=w.core.nRigid,
               switches_in_window=w.core.rigidSwitches - sw0, pieces_awake=tts.awake(w))
    return rec


def scene(name, scale, a):
    w, dt, state, start = tts.prepare(name, scale, a)
    kept, prep = {}, {}
    for on in (False, True):
        w.core.loadState(state)
        for k, v in settings(a, on).items():
            setattr(w.core, k, v)
        c0 = time.process_time()
        w.core.step(dt, a.prep)
        prep["on" if on else "off"] = {"cpu_s": time.process_time() - c0, "rigid": w.core.nRigid,
                                       "switches": w.core.rigidSwitches,
                                       "rigid_pieces": [i for i in range(w.core.nPieces) if w.core.rigid(i)]}
        kept[on] = w.core.saveState()
    print("rigidify gain: %s x%g prepared (%s): %s" % (name, scale, start, prep), flush=True)
    runs = {"off": [], "on": []}
    for r in range(a.rounds):
        for on in (False, True):
            rec = window(w, dt, kept[on], settings(a, on), a.steps)
            runs["on" if on else "off"].append(rec)
            print("rigidify gain: %s x%g round %d rigidify %-5s %.3f ms/step (CPU %.3f), %d rigid, %d switches; "
                  "load %.2f, others %.2f" % (name, scale, r, on, rec["ms_per_step"], rec["cpu_ms_per_step"],
                                              rec["rigid_at_end"], rec["switches_in_window"], rec["load1"],
                                              rec["other_cores"]), flush=True)
    gain = {}
    for key in ("ms_per_step", "cpu_ms_per_step"):
        ratios = [x[key] / y[key] for x, y in zip(runs["off"], runs["on"])]
        gain[key] = {"min": min(ratios), "median": statistics.median(ratios), "max": max(ratios)}
    loads = [x["load1"] for rs in runs.values() for x in rs]
    return {"name": name, "scale": scale, "dt": dt, "start": start, "prep_steps": a.prep, "prep": prep,
            "steps": a.steps, "rounds": a.rounds, "pieces": w.core.nPieces, "tets": w.core.nTets,
            "speedup_off_over_on": gain, "load1": {"min": min(loads), "median": statistics.median(loads),
                                                   "max": max(loads)}, "runs": runs}


def table(log):
    """The Markdown table of a log this script wrote (doc/dev/performance_notebook.md)."""
    d = json.load(open(log))
    a = d["args"]
    text = ("| scene | dt [s] | pieces rigid after %d steps (on) | ms/step off, median | ms/step on, median | "
            "speed-up min / median | switches in the windows | load1 |\n|---|---|---|---|---|---|---|---|\n"
            % a["prep"])
    for key, e in d["scenes"].items():
        med = lambda rs, k: statistics.median(x[k] for x in rs)  # noqa: E731
        g = e["speedup_off_over_on"]["ms_per_step"]
        text += "| %s (%d pieces) | %.3g | %d | %.3g | %.3g | %.2f / %.2f | %d | %.1f-%.1f |\n" % (
            key, e["pieces"], e["dt"], e["prep"]["on"]["rigid"], med(e["runs"]["off"], "ms_per_step"),
            med(e["runs"]["on"], "ms_per_step"), g["min"], g["median"],
            sum(x["switches_in_window"] for x in e["runs"]["on"]), e["load1"]["min"], e["load1"]["max"])
    text += ("\n(`%s`, %s: %d threads, rigidStrainRate %g /s, rigidTime %g s, rigidWakeStrain %g, rigidWakeLoad %g; "
             "%d steps a window, %d rounds, off and on interleaved)\n" % (
                 log, d["date"], a["threads"], a["rate"], a["dwell"], a["wakeStrain"], a["wakeLoad"], a["steps"],
                 a["rounds"]))
    return text


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--table":
        print(table(sys.argv[2]))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="two_rooks,forty_front")
    ap.add_argument("--scales", default="1")
    ap.add_argument("--prep", type=int, default=6000)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--after", type=int, default=1000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--dwell", type=float, default=5e-4)
    ap.add_argument("--wakeStrain", type=float, default=1e-5)
    ap.add_argument("--wakeLoad", type=float, default=0.1)
    ap.add_argument("--checkpoints", default="out/bench/time_to_solution")
    ap.add_argument("--log", default=None)
    a = ap.parse_args()
    _core.setThreads(a.threads)
    out = {"benchmark": "bench_rigidify", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "args": vars(a), "material": "Table 1, friction 0.1, implicit viscosity (Cholesky), as "
                                        "bench_time_to_solution.py", "host": tts.host(),
           "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "(libgomp default)"), "scenes": {}}
    for name in a.scenes.split(","):
        for scale in (float(s) for s in a.scales.split(",")):
            key = "%s_%s" % (name, "real_size" if scale == 1 else "%gx" % scale)
            out["scenes"][key] = e = scene(name, scale, a)
            print("rigidify gain: %s speed-up (off / on, wall) min %.2f median %.2f; load %.1f-%.1f" % (
                key, e["speedup_off_over_on"]["ms_per_step"]["min"], e["speedup_off_over_on"]["ms_per_step"]["median"],
                e["load1"]["min"], e["load1"]["max"]), flush=True)
    log = a.log or "bench/logs/rigidify_gain_%s.json" % time.strftime("%Y-%m-%d", time.gmtime())
    os.makedirs(os.path.dirname(log), exist_ok=True)
    with open(log, "w") as f:
        json.dump(out, f, indent=1)
    print("rigidify gain -> %s" % log)


if __name__ == "__main__":
    main()
