"""Time to solution of the shogi scenes (seed Figures 7-10) as users run them:
a YADE script with QdemEngine, a floor wall and NewtonIntegrator, set up as
scripts/shogi/domino.py sets them up, timed from the push through the first
hits (each awaited piece counts as hit when one of its nodes moves faster
than 2 % of sqrt(g H), domino.py's rule; the run goes on for a fifth more
steps after the last awaited hit, so the impacts themselves are timed).

Scenes: two rooks (piece 2 hit), the king and two pawns (both pawns hit),
and the 40-piece line through its first `--forty-hits` hits (default: the
second piece hit), with sleeping on as domino.py's sleep=0.003 sets it (the
most pieces asleep at once is recorded: with the soft material none fell
asleep before the first hits on 2026-11-24) and, with --forty-awake, off.
Each scene is built anew and run `--rounds` times, interleaved, on each thread count, the load and other
processes' CPU recorded per run (busy runs flagged, left out of 'clean').

    yade -n -j 2 -x scripts/bench/bench_shogi.py [--material soft] [--rounds 5] [--threads 1,2]
                                                 [--forty-hits 2] [--forty-awake] [--out out/bench]

--material soft (default, domino.py's default): E 1 MPa, no viscosity, real
size, dt 0.8 x stable.  --material table1: the seed's Table 1 at the scale
where 6.4e-6 s is stable (766x): the first hit takes ~180,000 steps there
(doc/shogi.md), minutes per run even with sleeping pieces.  Piece meshes
are made once per process (CGAL, not timed).  Writes shogi.json."""
import argparse
import functools
import json
import math
import os
import sys
import time

# (yade -x runs the script with its own __file__: the benchmark's folder is
# found from the script's path on the command line, else from the repository root)
_here = [os.path.dirname(os.path.abspath(p)) for p in sys.argv + [globals().get("__file__", "")]
         if p.endswith("bench_shogi.py")]
sys.path.insert(0, _here[0] if _here else os.path.abspath(os.path.join("scripts", "bench")))

import numpy as np  # noqa: E402
import qdem  # noqa: E402
from qdem.scenes import shogi  # noqa: E402
from yade import O, ForceResetter, FrictMat, NewtonIntegrator, utils  # noqa: E402

from benchutil import BUSY_RULE, LoadProbe, summarise  # noqa: E402

shogi.mesh = functools.lru_cache(maxsize=None)(shogi.mesh)   # mesh each kind once (CGAL, not timed)
G = 9.80665


def material(name):
    """(QdemMat, scale, dt or None) as scripts/shogi/domino.py chooses them."""
    if name == "table1":
        mat = qdem.QdemMat()
        return mat, math.ceil(shogi.stableScale(mat)), 6.4e-6
    return qdem.QdemMat(young=1e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4,
                        frictionPiece=0.1, frictionWall=0.5), 1.0, None


def build(name, matName, threads, sleep, count=None):
    """The scene in a fresh YADE scene; returns (pieces, H, engine)."""
    O.reset()
    mat, scale, dt = material(matName)
    H = max(shogi.KINDS[k][0] for k in shogi.SCENES[name]["kinds"]) * scale * 1e-3
    pieces = shogi.scene(name, mat, scale, count=count, push=math.sqrt(9.81 / H))
    floorMat = O.materials.append(FrictMat(young=max(1e7, mat.young), poisson=0.3, frictionAngle=0.5))
    O.bodies.append(utils.wall(0, axis=2, sense=1, material=floorMat))
    engine = qdem.QdemEngine(threads=threads, sleepVelocity=sleep * math.sqrt(G * H),
                             sleepTime=0.1 * math.sqrt(H / G))
    O.engines = [ForceResetter(), engine, NewtonIntegrator(gravity=(0, 0, -G))]
    O.dt = dt if dt else 0.8 * engine.stableDt()["combined"]
    return pieces, H, engine


def throughHits(pieces, H, awaited, maxSteps, chunk=50):
    """Runs from the push until every awaited piece is hit, then a fifth more
    steps.  Returns (steps, step of each awaited hit or None, wall s, the
    most pieces asleep at once, seen every `chunk` steps)."""
    core = qdem.defaultWorld().core
    hitSpeed = 0.02 * math.sqrt(G * H)
    hits = {i: None for i in awaited}
    asleep = 0
    t0 = time.perf_counter()
    while O.iter < maxSteps and any(v is None for v in hits.values()):
        O.run(chunk, True)
        asleep = max(asleep, core.nAsleep)
        for i in hits:
            if hits[i] is None and np.sqrt((pieces[i].vel ** 2).sum(1)).max() > hitSpeed:
                hits[i] = O.iter
    if all(v is not None for v in hits.values()):
        O.run(max(chunk, O.iter // 5), True)
        asleep = max(asleep, core.nAsleep)
    return O.iter, [hits[i] for i in awaited], time.perf_counter() - t0, asleep


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--material", choices=("soft", "table1"), default="soft")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", default="2")
    ap.add_argument("--forty-hits", type=int, default=1,
                    help="hits awaited in the 40-piece line (0: skip it; each is ~12,000 steps of 106,170 tets)")
    ap.add_argument("--forty-awake", action="store_true", help="also the 40-piece line without sleeping")
    ap.add_argument("--max-steps", type=int, default=60000, help="give up a run after this many steps")
    ap.add_argument("--out", default="out/bench")
    a = ap.parse_args(sys.argv[1:])
    if a.rounds < 1 or a.forty_hits < 0:
        ap.error("--rounds must be at least 1, --forty-hits at least 0")
    threadList = [int(t) for t in a.threads.split(",")]
    os.makedirs(a.out, exist_ok=True)
    # (label, scene, sleeping in units of sqrt(g H), awaited pieces, count)
    cases = [("two_rooks", "two_rooks", 0.0, [1], None), ("king_pawns", "king_pawns", 0.0, [1, 2], None)]
    if a.forty_hits:
        n = a.forty_hits + 1
        cases.append(("forty", "forty", 0.003, list(range(1, n)), None))
        if a.forty_awake:
            cases.append(("forty_awake", "forty", 0.0, list(range(1, n)), None))
    runs = {(c[0], t): [] for c in cases for t in threadList}
    info = {}
    for r in range(a.rounds):
        for t in threadList:
            for label, name, sleep, awaited, count in cases:
                pieces, H, engine = build(name, a.material, t, sleep, count)
                core = qdem.defaultWorld().core
                probe = LoadProbe()
                steps, hits, wall, asleep = throughHits(pieces, H, awaited, a.max_steps)
                rec = probe.finish(wall)
                rec.update(steps=steps, hit_steps=hits, wall_s=wall, ms_per_step=1e3 * wall / steps,
                           ms_per_step_on_cpu=1e3 * rec["own_cpu_s"] / t / steps,
                           wall_s_per_simulated_s=wall / (steps * O.dt), most_asleep=asleep,
                           complete=all(h is not None for h in hits))
                runs[(label, t)].append(rec)
                info[label] = {"scene": name, "pieces": len(pieces), "tets": core.nTets, "nodes": core.nNodes,
                               "dt": O.dt, "H_m": H, "sleep_velocity": engine.sleepVelocity,
                               "awaited_pieces (1 = the pushed one)": [i + 1 for i in awaited]}
                print("shogi round %d, %d thread(s), %-14s: %d steps, hits at %s, %.1f s wall, %.3f ms/step; "
                      "load %.2f (own %.2f), others %.2f%s%s"
                      % (r, t, label, steps, hits, wall, rec["ms_per_step"], rec["load1"], rec["own_load"],
                         rec["other_cores"], " BUSY" if rec["busy"] else "",
                         "" if rec["complete"] else "  NOT ALL HIT within --max-steps"), flush=True)
    scenes = {}
    for (label, t), rs in runs.items():
        s = dict(info[label], threads=t, material=a.material, steps=rs[0]["steps"],
                 first_hit_step=rs[0]["hit_steps"], runs=rs)
        s.update(summarise([x for x in rs if x["complete"]],
                           ["ms_per_step", "ms_per_step_on_cpu", "wall_s", "wall_s_per_simulated_s"]))
        scenes["%s_%dthreads" % (label, t)] = s
    out = {"benchmark": "bench_shogi", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "material": a.material, "rounds": a.rounds, "busy_rule": BUSY_RULE,
           "timed": "from the push through the awaited first hits, plus a fifth more steps; QdemEngine in "
                    "O.engines with ForceResetter, a floor wall and NewtonIntegrator (as scripts/shogi/domino.py)",
           "scenes": scenes}
    # Table 1 toward real size (scripts/shogi/scales.py writes the key
    # "scales" into this file; its runs take hours): kept from the file, or
    # taken from the newest committed log.
    path = os.path.join(a.out, "shogi.json")
    prev = {}
    if os.path.exists(path):
        with open(path) as f:
            prev = json.load(f)
    if "scales" in prev:
        out["scales"] = prev["scales"]
    else:
        import glob
        logs = sorted(glob.glob(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench", "logs",
                                             "shogi_scales_*.json")))
        if logs:
            with open(logs[-1]) as f:
                out["scales"] = dict(json.load(f), source="bench/logs/" + os.path.basename(logs[-1]))
    with open(path, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
