"""Only the effects a scene calls for (issue 6, part 3): the cost of each effect
switched on, switched off, and present with a zero value, on the 27-cube
Figure 6 scene at rest (165,888 tets, every face in contact), 2 threads.

The variants of all effects are timed round after round (`--rounds`), each
over the same `--steps` steps from its world's saved state, the order of on / off / zero turning from round to
round so that no variant always follows the same one; the load and other
processes' CPU are recorded per run and busy runs left out of 'clean'.  A
variant that does not exist (no zero-valued form of "point-polygon on", of
energy tracking, ...) is null: not measured, never copied from another.
Each run records the whole step and QDEM's own share of it (the core's
phase timers summed over the steps, per phase too), and each effect the
per-round ratios on/off and zero/off of both: the rounds interleave the
variants, so a ratio compares runs that saw the same machine, where medians
of whole runs swing 20-40 % on a shared machine.  The doc's table
(perf_tables.py effects) reads those ratios and the minima.

    /usr/bin/python3.11 scripts/bench/bench_effects.py [--steps 60] [--rounds 5] [--out out/bench]

Effects: viscosity, friction, edge-edge, point-polygon, energy sums, gravity
(World switches of the same names, QdemEngine attributes), contacts (all
contact phases on / off / the same cubes out of each other's reach), YADE
spheres (2,025 on the stack's top / none / 1 m above it, listed with no
piece near; and listed with every piece, as the engine's listAll does:
yadeSpheresAllPairs), and the stress output (per recorder frame, not per step: 'on' only)."""
import argparse
import json
import math
import os
import sys
import time

import numpy as np

import qdem
from qdem import _core

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_cubes27  # noqa: E402
from benchutil import BUSY_RULE, LoadProbe, stats, summarise  # noqa: E402

VARIANTS = ("on", "off", "zero")
UNITS = ("ms per step, median / min / max over the rounds; 'qdem': the core's phase timers summed (QDEM's own "
         "share of the step, wall clock), 'on_cpu': the process's CPU time over the 2 threads, beside the whole "
         "step; 'paired': per-round ratios of a variant to 'off' (the rounds interleave the variants)")
STATISTIC = ("paired ratios of interleaved rounds (median, min-max) for on/off and zero/off; the minimum over "
             "the rounds for ms per step")
OFF_OF = {"yadeSpheresAllPairs": "yadeSpheres"}   # an effect without an 'off' of its own: whose to compare with
DT = 6.4e-6


def settled(**matArgs):
    w = bench_cubes27.scene(mat=qdem.QdemMat(**matArgs) if matArgs else None)
    w.core.step(DT, 20)                      # contacts formed
    return w


NOTES = {
    "pointPolygon": "zero: no zero-valued form (not measured)",
    "energy": "zero: no zero-valued form (not measured)",
    "gravity": "off: the stack with gravity set to 0 now; zero: a stack built and settled without gravity",
    "contacts": "off: point-polygon and edge-edge switched off; zero: the same 27 cubes 5 m apart, 10 m up "
                "(no piece can reach another)",
    "yadeSpheres": "on: 2,025 spheres resting on the stack's top, each listed with every piece; off: none; "
                   "zero: the same spheres 1 m above it, listed with no piece near (in a YADE scene the "
                   "engine does not hand over spheres the collider finds near no piece)",
    "yadeSpheresAllPairs": "zero: the spheres 1 m above the stack, each listed with all 27 pieces (54,675 "
                           "pairs checked per step: a broad phase that listed every pair)",
}


def timed(world, steps):
    """(ms per step, load record) of `steps` steps after a 3-step warm-up,
    stepped one by one.  The record has the step on CPU (CPU time over the 2
    threads) and QDEM's own share of the step: the core's phase timers
    (World.timings, wall time of each phase of the last step) summed over
    the steps, per phase and in all ("qdem_ms_per_step").  What the step
    takes beyond them is the Python call and, in a YADE scene, YADE's own
    engines; here (a bare core world) only the call."""
    world.core.step(DT, 3)
    phases = {}
    probe = LoadProbe()
    t = time.perf_counter()
    for _ in range(steps):
        world.core.step(DT, 1)
        for k, v in world.core.timings.items():
            phases[k] = phases.get(k, 0.0) + v
    wall = time.perf_counter() - t
    rec = probe.finish(wall)
    rec["ms_per_step_on_cpu"] = 1e3 * rec["own_cpu_s"] / 2 / steps
    rec["qdem_ms_per_step"] = 1e3 * sum(phases.values()) / steps
    rec["phases_ms_per_step"] = {k: 1e3 * v / steps for k, v in phases.items()}
    return 1e3 * wall / steps, rec


def paired(runs, num, den, key):
    """Per-round ratios num/den of `key` (the rounds interleave the
    variants, so both see the same machine): stats, or None."""
    a, b = runs.get(num) or [], runs.get(den) or []
    return stats([x[key] / y[key] for x, y in zip(a, b) if x.get(key) and y.get(key)])


KEYS = {"whole": "ms_per_step", "cpu": "ms_per_step_on_cpu", "qdem": "qdem_ms_per_step"}


def summariseEffect(byVariant, offRuns):
    """The figures of one effect from its runs (variant -> run records):
    clean / all statistics of the whole step, of it on CPU and of QDEM's
    share, and the paired per-round ratios of 'on' and 'zero' to 'off'
    (offRuns: the 'off' runs to compare with, the effect's own or another's)."""
    e = {"clean": {}, "all": {}, "on_cpu": {"clean": {}, "all": {}}, "qdem": {"clean": {}, "all": {}},
         "runs": byVariant}
    for v, rs in byVariant.items():
        s = summarise(rs, list(KEYS.values()))
        e["clean"][v], e["all"][v] = s["clean"]["ms_per_step"], s["all"]["ms_per_step"]
        for group, key in (("on_cpu", "ms_per_step_on_cpu"), ("qdem", "qdem_ms_per_step")):
            e[group]["clean"][v], e[group]["all"][v] = s["clean"][key], s["all"][key]
    # The robust figures: ratios within each round (both variants ran back
    # to back, on the same machine), of QDEM's share (wall), of the process's
    # CPU time (in this bare core world all QDEM's but the Python call) and
    # of the whole step.
    withOff = dict(byVariant, off=offRuns)
    e["paired"] = {"%s_over_off" % v: {name: paired(withOff, v, "off", key) for name, key in KEYS.items()}
                   for v in ("on", "zero")}
    return e


def summariseStress(frames):
    """The stress output's figures (ms per recorder frame, 'on' only): all
    of it QDEM's; on CPU from the frames' CPU time over the 2 threads."""
    for r in frames:
        r["ms_per_step_on_cpu"] = 1e3 * r["own_cpu_s"] / 2
    s = summarise(frames, ["ms_per_step", "ms_per_step_on_cpu"])

    def on(key, which):
        return {"on": s[which][key], "off": None, "zero": None}

    return {"clean": on("ms_per_step", "clean"), "all": on("ms_per_step", "all"),
            "qdem": {"clean": on("ms_per_step", "clean"), "all": on("ms_per_step", "all")},
            "on_cpu": {"clean": on("ms_per_step_on_cpu", "clean"), "all": on("ms_per_step_on_cpu", "all")},
            "paired": {"%s_over_off" % v: dict.fromkeys(KEYS) for v in ("on", "zero")},
            "runs": {"on": frames}, "note": "ms per recorder frame (stress is computed only when a recorder asks)"}


def resummarise(path):
    """Recompute an effects.json's figures from the runs it keeps."""
    with open(path) as f:
        d = json.load(f)
    for name, e in d["effects"].items():
        if name == "stressOutput":
            d["effects"][name] = summariseStress(e["runs"]["on"])
            continue
        note = NOTES.get(name, e.get("note"))
        d["effects"][name] = summariseEffect(e["runs"], d["effects"][OFF_OF.get(name, name)]["runs"]["off"])
        if note:
            d["effects"][name]["note"] = note
    d["statistic"] = STATISTIC
    d["units"] = UNITS
    with open(path, "w") as f:
        json.dump(d, f, indent=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--out", default="out/bench")
    ap.add_argument("--resummarise", metavar="EFFECTS_JSON", help="recompute the figures of a written "
                    "effects.json from the runs it keeps (no timing)")
    a = ap.parse_args()
    if a.resummarise:
        return resummarise(a.resummarise)
    if a.steps < 1 or a.rounds < 1:
        ap.error("--steps and --rounds must be at least 1")
    os.makedirs(a.out, exist_ok=True)
    _core.setThreads(2)
    base = settled()
    noVisc = settled(viscosity=0.0)
    noFric = settled(frictionPiece=0.0, frictionWall=0.0)
    noEdges = bench_cubes27.scene()
    noEdges.core.edgeFeatureAngle = math.pi   # no edge is a feature edge: nothing to test
    noEdges.core.step(DT, 20)
    flat = bench_cubes27.scene()
    flat.core.gravity = (0, 0, 0)
    flat.core.step(DT, 20)
    apart = qdem.World()                       # the same cubes out of each other's reach
    for i in range(27):
        apart.addPiece(qdem.boxMesh((4, 4, 4), (8, 8, 8), tetsPerCell=12), qdem.QdemMat(), pos=(5.0 * i, 0, 10))

    # YADE spheres (what QdemEngine hands over from the scene): 2,025 spheres
    # resting on the top of the stack, the same spheres 1 m above it, or none.
    top = base.core.pos[:, 2].max()
    R = 0.05
    g = np.linspace(-5.5, 5.5, 45)
    xy = np.array([(x, y) for x in g for y in g])
    k, npc = len(xy), base.core.nPieces
    props = [np.full(k, v) for v in (R, 1e8, 0.3, 0.5, -1.0, 1.0)]
    pairs = (np.arange(0, k * npc + 1, npc, dtype=np.int32), np.tile(np.arange(npc, dtype=np.int32), k))

    noPairs = (np.zeros(k + 1, dtype=np.int32), np.zeros(0, dtype=np.int32))

    def spheres(z, listed=pairs):
        """The spheres QdemEngine hands over: ids, properties, and for each
        sphere the pieces YADE's collider found near it (`listed`)."""
        if z is None:
            base.core.setSpheres(np.zeros(0, np.int32), *[np.zeros(0)] * 6, np.zeros(1, np.int32),
                                 np.zeros(0, np.int32))
        else:
            base.core.setSpheres(np.arange(k, dtype=np.int32), *props, *listed)
            base.core.setSphereStates(np.column_stack([xy, np.full(k, z)]), np.zeros((k, 3)), np.zeros((k, 3)))
        return base

    def switch(attr, value, world=None):
        def go():
            setattr(base.core, attr, value)
            return base
        return go if world is None else (lambda: world)

    def contacts(on):
        def go():
            base.core.pointPolygonOn = base.core.edgeEdgeOn = on
            return base
        return go

    # effect -> {variant: set-up returning the world to step, or None (no such variant)};
    # after each variant the base world is put back as it was (all on, no spheres).
    G = (0, 0, -9.80665)
    effects = {
        "viscosity": {"on": switch("viscosityOn", True), "off": switch("viscosityOn", False),
                      "zero": switch(None, None, noVisc)},
        "friction": {"on": switch("frictionOn", True), "off": switch("frictionOn", False),
                     "zero": switch(None, None, noFric)},
        "edgeEdge": {"on": switch("edgeEdgeOn", True), "off": switch("edgeEdgeOn", False),
                     "zero": switch(None, None, noEdges)},
        "pointPolygon": {"on": switch("pointPolygonOn", True), "off": switch("pointPolygonOn", False), "zero": None},
        "energy": {"on": switch("trackEnergy", True), "off": switch("trackEnergy", False), "zero": None},
        "gravity": {"on": switch("gravity", G), "off": switch("gravity", (0, 0, 0)), "zero": switch(None, None, flat)},
        "contacts": {"on": contacts(True), "off": contacts(False), "zero": switch(None, None, apart)},
        "yadeSpheres": {"on": lambda: spheres(top + 0.04 + R - 0.002), "off": lambda: spheres(None),
                        "zero": lambda: spheres(top + 1.0, noPairs)},
        "yadeSpheresAllPairs": {"on": None, "off": None, "zero": lambda: spheres(top + 1.0)},
    }

    def restore():
        c = base.core
        c.viscosityOn = c.frictionOn = c.edgeEdgeOn = c.pointPolygonOn = True
        c.trackEnergy = False
        c.gravity = G
        spheres(None)

    # Every variant starts from its world's state as settled: without this
    # the base world, stepped by all its variants, drifts away from the
    # zero-valued worlds, stepped only by theirs (the stack keeps settling:
    # the first version of this script compared worlds hundreds of steps apart).
    worlds = [base, noVisc, noFric, noEdges, flat, apart]
    states = [w.core.saveState() for w in worlds]

    def reload():
        for w, st in zip(worlds, states):
            w.core.loadState(st)

    restore()
    runs = {e: {v: [] for v in VARIANTS} for e in effects}
    for r in range(a.rounds):
        order = VARIANTS[r % 3:] + VARIANTS[:r % 3]
        for name, variants in effects.items():
            for v in order:
                if variants[v] is None:
                    continue
                reload()
                ms, rec = timed(variants[v](), a.steps)
                restore()
                rec["ms_per_step"] = ms
                runs[name][v].append(rec)
                print("round %d %-12s %-4s %.2f ms/step; load %.2f (own %.2f), others %.2f%s"
                      % (r, name, v, ms, rec["load1"], rec["own_load"], rec["other_cores"],
                         " BUSY" if rec["busy"] else ""), flush=True)
    res = {}
    for name, byVariant in runs.items():
        res[name] = summariseEffect(byVariant, runs[OFF_OF.get(name, name)]["off"])
        if name in NOTES:
            res[name]["note"] = NOTES[name]
    # Stress output: computed only when a recorder asks (per frame, not per step).
    frames = []
    for _ in range(a.rounds):
        probe = LoadProbe()
        t = time.perf_counter()
        base.core.stress()
        wall = time.perf_counter() - t
        rec = probe.finish(wall)
        rec["ms_per_step"] = 1e3 * wall
        frames.append(rec)
    res["stressOutput"] = summariseStress(frames)
    out = {"benchmark": "bench_effects", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "tets": base.core.nTets, "threads": 2, "steps": a.steps, "rounds": a.rounds, "busy_rule": BUSY_RULE,
           "units": UNITS, "statistic": STATISTIC, "effects": res}
    with open(os.path.join(a.out, "effects.json"), "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
