"""Table 1's material toward real size (doc/shogi.md, "Toward real size"):
the two rooks (seed Figure 7) at 766, 100, 10 and 1 times real size, with
the Kelvin-Voigt viscosity integrated explicitly and implicitly
(QdemEngine.viscousIntegration).

    /usr/bin/python3.11 scripts/shogi/scales.py [--steps 40] [--rounds 3] [--out out/bench]
        [--log bench/logs/shogi_scales_<date>.json]

1. The first elastic mode's damping ratio xi = beta omega_1 / 2 of the rook
   at each scale (qdem.modes; omega_1 goes as 1/scale).
2. Cost: short core runs of the scene as built (pieces standing, the first
   tipped) on one thread, explicit and implicit interleaved `rounds` times
   (medians): CPU milliseconds per step (one thread: the wall time on a quiet
   core; the machine is shared, so CPU time is the steadier measure), the
   conjugate-gradient iterations per step, and the cost per simulated second
   at 0.8 x each integration's stable step (stableDt()['combinedExplicit'] /
   ['combinedImplicit']).  At small scales explicit runs are never made in
   full: their cost is this per-step cost times the step count, simulated
   time / step.  Implicit twice: each solve started from the last step's
   velocity change (the default, QdemEngine.viscousWarmStart) and from zero
   ("implicit_cold").
3. The runs of scripts/shogi/scales.table (scripts/shogi/domino.py, YADE),
   when present under out/shogi: first hits and falls, with their times
   brought to 766x by Froude scaling (t x sqrt(766 / scale)).

Writes the key "scales" of out/bench/shogi.json (the rest of that file is
scripts/bench/bench_shogi.py's) and, with --log, the same as a standalone
JSON for bench/logs.
"""
import argparse
import glob
import json
import math
import os
import statistics
import sys
import time

import qdem
from qdem import _core, modes
from qdem.scenes import shogi

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from benchutil import floorAndGravity  # noqa: E402

SCALES = (766, 100, 10, 1)
DT_FACTOR = 0.8                         # as domino.py's dtFactor
G = 9.80665


def table1Scale():
    """The scale at which Table 1's 6.4e-6 s is stable with explicit
    viscosity (doc/shogi.md), as domino.py keeps it (out/shogi/table1_scale.json)."""
    path, mat = "out/shogi/table1_scale.json", qdem.QdemMat(frictionPiece=0.1)
    key = json.dumps(mat.dict(), sort_keys=True)
    if os.path.exists(path) and key in json.load(open(path)):
        return json.load(open(path))[key]
    return math.ceil(shogi.stableScale(mat))


def material(scale, stable):
    """Table 1 with the particle radius scaled with the pieces (0.04 m at 766x)."""
    return qdem.QdemMat(frictionPiece=0.1, radius=qdem.QdemMat().radius * scale / stable)


VARIANTS = ("explicit", "implicit", "implicit_cold")


def build(scale, stable, variant):
    w = qdem.World()
    shogi.scene("two_rooks", material(scale, stable), scale, world=w)
    floorAndGravity(w, G)
    w.core.viscousIntegration = 0 if variant == "explicit" else 1
    w.core.viscousWarmStart = variant != "implicit_cold"
    return w


def cpuMsPerStep(w, dt, steps):
    """CPU ms per step over `steps` steps, and the CG iterations per step."""
    its = 0
    t = time.process_time()
    for _ in range(steps):
        w.core.step(dt, 1)
        its += w.core.counts.get("viscousIterations", 0)
    return 1e3 * (time.process_time() - t) / steps, its / steps


def timing(scale, stable, steps, rounds):
    worlds = {name: build(scale, stable, name) for name in VARIANTS}
    limits = worlds["implicit"].stableDt()
    dts = {name: DT_FACTOR * limits["combinedExplicit" if name == "explicit" else "combinedImplicit"]
           for name in VARIANTS}
    for name, w in worlds.items():
        w.core.step(dts[name], 3)  # warm-up: lists, layouts
    samples = {name: [] for name in worlds}
    for _ in range(rounds):  # interleaved: both see the same machine load
        for name, w in worlds.items():
            samples[name].append(cpuMsPerStep(w, dts[name], steps))
    out = {"stable_dt_explicit": limits["combinedExplicit"], "stable_dt_implicit": limits["combinedImplicit"],
           "limited_by_explicit": "viscosity" if limits["viscous"] <= limits["combinedExplicit"] * (1 + 1e-12)
           else limits["limitedBy"], "elastic_dt": limits["elastic"], "viscous_dt": limits["viscous"],
           "contact_dt": limits["contact"]}
    for name in worlds:
        ms = statistics.median(s[0] for s in samples[name])
        out[name] = {"dt": dts[name], "cpu_ms_per_step": ms, "cpu_ms_per_step_samples": [s[0] for s in samples[name]],
                     "cg_iterations_per_step": statistics.median(s[1] for s in samples[name]),
                     "steps_per_simulated_s": 1.0 / dts[name],
                     "cpu_s_per_simulated_s": 1e-3 * ms / dts[name]}
    out["explicit_over_implicit"] = out["explicit"]["cpu_s_per_simulated_s"] / out["implicit"]["cpu_s_per_simulated_s"]
    out["cold_over_warm"] = out["implicit_cold"]["cpu_s_per_simulated_s"] / out["implicit"]["cpu_s_per_simulated_s"]
    return out


def progress(log):
    """(step, simulated time) of the last progress line in a domino.py log
    ('qdem: step N  t=T s ...'), the wall time since the log was started, and
    the scene's line: how far a run that has not written its first frame got."""
    last, head = None, None
    for line in open(log):
        if line.startswith("qdem: step "):
            f = line.split()
            last = (int(f[2]), float(f[3][2:]))
        elif line.startswith("shogi: two_rooks"):
            head = line.strip()
    return last, head


def runs(stable):
    """The scales.table runs found under out/shogi (domino.py's hits.json)."""
    found = []
    for path in sorted(glob.glob("out/shogi/two_rooks_mu*_table1_x*/hits.json")):
        r = json.load(open(path))
        froude = math.sqrt(stable / r["scale"])   # times at this scale x froude = times at 766x
        found.append({
            "run": os.path.basename(os.path.dirname(path)), "scale": r["scale"], "frictionPiece": r["frictionPiece"],
            "viscous": r.get("viscous", "explicit"), "dt": r["dt"], "settle_s": r["settle_s"],
            "simulated_s": r["simulated_s"], "simulated_s_at_766x": r["simulated_s"] * froude,
            "steps": r.get("steps"), "cg_iterations_per_step": r.get("cg_iterations_per_step"),
            "wall_s": r["wall_s"], "wall_s_per_simulated_s": r["wall_s_per_simulated_s"],
            "firstHit_s": r["firstHit_s"], "fallen_s": r["fallen_s"],
            "firstHit_s_at_766x": [None if t is None else t * froude for t in r["firstHit_s"]],
            "fallen_s_at_766x": [None if t is None else t * froude for t in r["fallen_s"]]})
    return found


def hms(seconds):
    return "%.0f s" % seconds if seconds < 600 else ("%.1f h" % (seconds / 3600) if seconds < 2 * 86400
                                                     else "%.1f days" % (seconds / 86400))


def markdown(res):
    """The tables of doc/shogi.md, "Toward real size"."""
    print("\n| scale | explicit dt | ms per step | CPU s per simulated s | implicit dt | CG iterations (from 0) | "
          "ms per step (from 0) | CPU s per simulated s | explicit / implicit |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for key, r in res["scales"].items():
        e, i, c = r["explicit"], r["implicit"], r.get("implicit_cold")
        print("| %s | %.3g s | %.2g | %.2g | %.3g s | %.0f%s | %.2g%s | %.2g | %.2g |" % (
            key, e["dt"], e["cpu_ms_per_step"], e["cpu_s_per_simulated_s"], i["dt"], i["cg_iterations_per_step"],
            " (%.0f)" % c["cg_iterations_per_step"] if c else "", i["cpu_ms_per_step"],
            " (%.2g)" % c["cpu_ms_per_step"] if c else "", i["cpu_s_per_simulated_s"], r["explicit_over_implicit"]))
    print("\n| scale | second rook hit at | explicit: CPU to the hit | implicit: CPU to the hit |")
    print("| --- | --- | --- | --- |")
    for key, r in res["scales"].items():
        if "first_hit_s" in r:
            print("| %s | %.4g s | %s | %s |" % (key, r["first_hit_s"], hms(r["explicit"]["cpu_s_to_first_hit"]),
                                               hms(r["implicit"]["cpu_s_to_first_hit"])))
    print("\n| scale | viscosity | friction | dt | simulated (at 766x) | second rook hit (at 766x) | "
          "first rook fallen (at 766x) | second rook fallen (at 766x) | CG iterations per step | "
          "wall s per simulated s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def t(v, v766):
        return "-" if v is None else ("%.4g s (%.4g s)" % (v, v766) if v != v766 else "%.4g s" % v)
    for r in sorted(res["runs"], key=lambda r: (-r["scale"], r["viscous"], r["frictionPiece"])):
        print("| %g | %s | %g | %.3g s | %s | %s | %s | %s | %s | %.3g |" % (
            r["scale"], r["viscous"], r["frictionPiece"], r["dt"], t(r["simulated_s"], r["simulated_s_at_766x"]),
            t(r["firstHit_s"][1], r["firstHit_s_at_766x"][1]), t(r["fallen_s"][0], r["fallen_s_at_766x"][0]),
            t(r["fallen_s"][1], r["fallen_s_at_766x"][1]),
            "%.0f" % r["cg_iterations_per_step"] if r["viscous"] == "implicit" else "-", r["wall_s_per_simulated_s"]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--out", default="out/bench")
    ap.add_argument("--log", default=None, help="also write the result here (bench/logs/...)")
    ap.add_argument("--scales", default=",".join(map(str, SCALES)))
    ap.add_argument("--progress", action="append", default=[], metavar="RUN=LOG",
                    help="a run with no frame written yet: its last progress line in domino.py's log LOG")
    ap.add_argument("--runs-only", action="store_true",
                    help="keep the damping ratios and timings of --log (an earlier run) and gather the runs again")
    a = ap.parse_args()
    _core.setThreads(1)
    stable = table1Scale()
    if a.runs_only:
        res = json.load(open(a.log))
    else:
        res = {"scene": "two_rooks", "threads": 1, "table1_scale": stable, "dt_factor": DT_FACTOR,
               "steps": a.steps, "rounds": a.rounds, "scales": {}}
    rook = None if a.runs_only else shogi.mesh("rook")
    for s in ([] if a.runs_only else (float(x) for x in a.scales.split(","))):
        mat = material(s, stable)
        xi = modes.dampingRatio(rook.scaled(s), mat)
        omega = modes.naturalFrequencies(rook.scaled(s), mat, count=1)[0]
        r = {"first_mode_rad_per_s": float(omega), "first_mode_damping_ratio": float(xi),
             "height_m": shogi.KINDS["rook"][0] * s * 1e-3,
             "froude_time_unit_s": math.sqrt(shogi.KINDS["rook"][0] * s * 1e-3 / G)}
        r.update(timing(s, stable, a.steps, a.rounds))
        res["scales"]["%g" % s] = r
        print("scale %5g: xi_1 %.3g; explicit dt %.3g s %.3f ms/step %.3g s/s; implicit dt %.3g s %.3f ms/step "
              "(%.0f CG its; %.0f from 0) %.3g s/s; ratio %.3g" % (
                  s, xi, r["explicit"]["dt"], r["explicit"]["cpu_ms_per_step"], r["explicit"]["cpu_s_per_simulated_s"],
                  r["implicit"]["dt"], r["implicit"]["cpu_ms_per_step"], r["implicit"]["cg_iterations_per_step"],
                  r["implicit_cold"]["cg_iterations_per_step"], r["implicit"]["cpu_s_per_simulated_s"], r["explicit_over_implicit"]), flush=True)
    res["runs"] = runs(stable)
    for item in a.progress:
        run, _, log = item.partition("=")
        (step, t), head = progress(log)
        res.setdefault("progress", {})[run] = {"log": log, "step": step, "simulated_s": t, "start": head,
                                               "simulated_s_at_766x": t * math.sqrt(stable / float(
                                                   run.split("_x")[1].split("_")[0]))}
        print("progress %s: step %d, t = %.4g s" % (run, step, t))
    # The cost of reaching the first hit at every scale: the 766x explicit
    # run's first hit of the second rook, brought to each scale by Froude
    # scaling, times each integration's cost per simulated second.
    ref = [r for r in res["runs"] if r["scale"] == stable and r["viscous"] == "explicit" and r["firstHit_s"][1]]
    if ref:
        tHit = ref[0]["firstHit_s"][1]
        for key, r in res["scales"].items():
            t = tHit * math.sqrt(float(key) / stable)
            r["first_hit_s"] = t
            for name in VARIANTS:
                if name in r:
                    r[name]["cpu_s_to_first_hit"] = t * r[name]["cpu_s_per_simulated_s"]
    for r in res["runs"]:
        print("run %s: %.4g s simulated (%.4g s at 766x), first hits %s, fallen %s" % (
            r["run"], r["simulated_s"], r["simulated_s_at_766x"], r["firstHit_s_at_766x"], r["fallen_s_at_766x"]))
    markdown(res)
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "shogi.json")
    bench = json.load(open(path)) if os.path.exists(path) else {}
    bench["scales"] = res
    json.dump(bench, open(path, "w"), indent=2)
    if a.log:
        os.makedirs(os.path.dirname(a.log), exist_ok=True)
        json.dump(res, open(a.log, "w"), indent=2)


if __name__ == "__main__":
    main()
