"""What a step of the forty-piece line costs at REAL size (Table 1's material,
no 766x scaling, implicit viscosity at 0.8 of its stable step), measured
from a checkpoint at the front, on 2 threads: the baseline the time to
solution of the whole line is judged against.

    PYTHONPATH=build/python OMP_WAIT_POLICY=passive /usr/bin/python3.11 \
        scripts/shogi/time_to_solution_baseline.py [--friction 0.1] [--steps 300] [--rounds 3] [--threads 2] \
        [--preconditioner cholesky|jacobi] \
        [--gap 3e-4] [--after 1000] [--dir out/shogi/forty_real_front] \
        [--log bench/logs/time_to_solution_baseline.json]

1. The checkpoint (made once, kept in --dir; a few minutes on 2 cores):
   the line built as scripts/shogi/cost_in_run.py builds its scenes (bare
   core world, the floor as stiff as the pieces, gravity), Table 1's
   material at scale 1 with the particle radius scaled alike (0.04 m / 766),
   implicit viscosity at 0.8 of the stable step.  From rest the king would
   take ~0.04 s (~290,000 steps, hours on a shared machine) to reach the
   rook, so it is placed `--gap` from the rook, turned as a rigid body about
   its base's front edge, with the angular velocity its push and fall give
   it there (energy), and stepped until the rook is hit (speed above 2 % of
   sqrt(g H), as domino.py's hits.json counts it) and `--after` steps more.
   Pieces three and on are held (dynamic = False): standing still ahead of
   the front, they cost what sleeping pieces cost in a run with `sleep`
   (left out of the step).
2. The timing: the checkpoint loaded into a freshly built world, `--steps`
   steps stepped one by one `--rounds` times, the state reloaded before each
   round so that every round covers the same steps; wall and CPU time, CG
   iterations of the implicit viscous solve per step, pieces awake, the load
   average before and after each round and other processes' CPU during it
   (benchutil.LoadProbe).  Min and median over the rounds.
"""
import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np
from scipy.spatial import ConvexHull

import qdem
from qdem import _core
from qdem.scenes import shogi

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from benchutil import BUSY_RULE, floorAndGravity, timedWindow  # noqa: E402
import scales  # noqa: E402  (scripts/shogi, this script's folder)

G = 9.80665
DT_FACTOR = 0.8          # as domino.py's dtFactor
HELD_FROM = 2            # pieces from this index on are held until the front reaches them


def table1Scale():
    """scales.table1Scale() (766; meshing the eight kinds takes minutes),
    kept in out/shogi/table1_scale.json as domino.py keeps it."""
    scale = scales.table1Scale()
    path, key = "out/shogi/table1_scale.json", json.dumps(qdem.QdemMat(frictionPiece=0.1).dict(), sort_keys=True)
    known = json.load(open(path)) if os.path.exists(path) else {}
    if key not in known:
        known[key] = scale
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w") as f:
            json.dump(known, f, indent=1)
    return scale


def host():
    """The CPU model and its vector extensions (lscpu)."""
    out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    info = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
    flags = info.get("Flags", "").split()
    return {"model": info.get("Model name", "").strip(), "cpus": int(info.get("CPU(s)", "0").strip() or 0),
            "avx2": "avx2" in flags, "avx512f": "avx512f" in flags, "fma": "fma" in flags,
            "python": platform.python_version()}


def build(friction):
    """The real-size forty-piece line in a bare core world: (world, pieces, H)."""
    w = qdem.World()
    # Table 1 at real size: the particle radius scaled with the pieces, as
    # cost_in_run.py and domino.py scale it (0.04 m at 766x, 52 um here).
    mat = qdem.QdemMat(frictionPiece=friction, radius=qdem.QdemMat().radius / table1Scale())
    pieces = shogi.scene("forty", mat, 1.0, world=w)
    floorAndGravity(w, G, young=max(1e7, mat.young))  # the floor as domino.py's
    w.core.viscousIntegration = 1                        # implicit viscosity
    w.core.viscousWarmStart = True                      # the default: each solve from the last step's change
    H = max(shogi.KINDS[k][0] for k in shogi.SCENES["forty"]["kinds"]) * 1e-3
    return w, pieces, H


def hold(pieces, front):
    for i, p in enumerate(pieces):
        p.dynamic = i < front


def awake(w):
    c = w.core
    return sum(1 for i in range(c.nPieces) if c.dynamic(i) and not c.asleep(i))


def tipTowardRook(pieces, radius, gap, push):
    """Put the king where it is `gap` from the rook, turned about the front
    edge of its base as a rigid body, with the angular velocity it has there after the
    push and its fall (energy: I w^2 / 2 = I w0^2 / 2 + m g (z0 - z)).
    Returns (angle, angular velocity).  At real size the king deforms by
    ~1e-6 of its size on the way: the rigid approach stands for the
    overdamped one (its stress relaxes within the first steps)."""
    king, rook = pieces[0], pieces[1]
    P = king.pos.copy()
    base = P[:, 2] < P[:, 2].min() + 1e-3 * (P[:, 2].max() - P[:, 2].min())
    pivot = np.array([P[base, 0].max(), 0.0, P[:, 2].min()])   # the front edge of its base: it tips about it
    X0, m = P - pivot, king.mass.copy()
    # The rook is convex: a point's distance to it is at least the largest
    # signed distance to the planes of its hull's faces.
    hull = ConvexHull(rook.pos)
    normals, offsets = hull.equations[:, :3], hull.equations[:, 3]

    def clearance(X):
        return float((X @ normals.T + offsets).max(axis=1).min())

    def turned(th):
        c, s = math.cos(th), math.sin(th)
        return X0 @ np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]).T   # tips +z toward +x

    lo, hi = 0.0, 0.5 * math.pi
    for _ in range(60):                                 # bisection: the king's front just `gap` from the rook
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clearance(turned(mid) + pivot) > gap else (lo, mid)
    th = lo
    X = turned(th)
    inertia = float((m * (X0[:, 0] ** 2 + X0[:, 2] ** 2)).sum())
    drop = float((m * (X0[:, 2] - X[:, 2])).sum())          # m (z0 - z) summed over the nodes
    w = math.sqrt(push ** 2 + 2.0 * G * drop / inertia)
    king.pos[:] = X + pivot
    king.vel[:] = np.cross([0.0, w, 0.0], X)
    return th, w


def makeCheckpoint(a, path):
    w, pieces, H = build(a.friction)
    limits = w.stableDt()
    dt = DT_FACTOR * limits["combinedImplicit"]
    radius = qdem.QdemMat().radius / table1Scale()
    th, omega = tipTowardRook(pieces, radius, a.gap, math.sqrt(9.81 / H))
    hold(pieces, HELD_FROM)
    hitSpeed = 0.02 * math.sqrt(G * H)
    print("baseline: forty at real size, %d tets, dt %.4g s (stable %.4g, %s); king turned %.1f deg, %.3g mm "
          "from the rook, at %.3g rad/s; pieces %d-%d held" % (
              w.core.nTets, dt, limits["combinedImplicit"], limits["limitedBy"], math.degrees(th), 1e3 * a.gap,
              omega, HELD_FROM + 1, len(pieces)), flush=True)
    _core.setThreads(2)
    start, steps, hitAt = time.time(), 0, None
    chunk = 100
    while True:
        w.core.step(dt, chunk)
        steps += chunk
        if hitAt is None and np.linalg.norm(pieces[1].velocity) > hitSpeed:
            hitAt = (steps, w.core.time)
            print("baseline: rook hit at t = %.5g s (step %d, %.0f s wall)" % (w.core.time, steps,
                                                                              time.time() - start), flush=True)
        if hitAt is not None and steps >= hitAt[0] + a.after:
            break
        if steps % 1000 == 0:
            print("baseline: t = %.5g s, step %d, %.0f s wall, %d CG its in the last step" % (
                w.core.time, steps, time.time() - start, w.core.counts.get("viscousIterations", 0)), flush=True)
        if steps > 100000:
            raise RuntimeError("the rook was not hit within 100,000 steps: the set-up is wrong")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    qdem.saveState(path, world=w, dt=dt, hit_s=hitAt[1], hit_step=hitAt[0], steps=steps,
                   wall_s=time.time() - start, friction=a.friction, king_angle_deg=math.degrees(th),
                   king_omega=omega, gap_m=a.gap)
    print("baseline: checkpoint at t = %.5g s written to %s" % (w.core.time, path), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--friction", type=float, default=0.1)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--after", type=int, default=1000, help="steps past the rook's hit before the checkpoint")
    ap.add_argument("--gap", type=float, default=3e-4, help="the king's start: this far from the rook [m]")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--preconditioner", choices=["cholesky", "jacobi"], default="cholesky",
                    help="the implicit viscous solve's (viscousPreconditioner)")
    ap.add_argument("--dir", default="out/shogi/forty_real_front")
    ap.add_argument("--log", default="bench/logs/time_to_solution_baseline.json")
    a = ap.parse_args()
    if a.steps < 1 or a.rounds < 1:
        ap.error("--steps and --rounds must be at least 1")
    path = os.path.join(a.dir, "checkpoint_mu%g.npz" % a.friction)
    if not os.path.exists(path):
        makeCheckpoint(a, path)
    w, pieces, H = build(a.friction)
    hold(pieces, HELD_FROM)
    extra = qdem.loadState(path, world=w)
    dt = float(extra["dt"])
    state = w.core.saveState()
    _core.setThreads(a.threads)
    w.core.viscousPreconditioner = {"jacobi": 0, "cholesky": 1}[a.preconditioner]
    runs = []
    for r in range(a.rounds):
        w.core.loadState(state)
        w.core.step(dt, 3)                  # lists and thread layout built anew after loading
        rec, its, phases = timedWindow(w, dt, a.steps)
        wall, cpu = rec["wall_s"], rec["cpu_s"]
        rec.update(ms_per_step=1e3 * wall / a.steps, steps_per_s=a.steps / wall,
                   wall_s_per_simulated_s=wall / (a.steps * dt), cpu_s_per_simulated_s=cpu / (a.steps * dt),
                   cg_iterations_per_step=its / a.steps, pieces_awake=awake(w),
                   phases_ms_per_step={k: 1e3 * v / a.steps for k, v in phases.items()})
        runs.append(rec)
        print("round %d: %.2f ms/step wall, %.0f wall s / simulated s (CPU %.0f), %.1f CG its/step, %d awake; "
              "load %.2f -> %.2f, others %.2f%s" % (
                  r, rec["ms_per_step"], rec["wall_s_per_simulated_s"], rec["cpu_s_per_simulated_s"],
                  rec["cg_iterations_per_step"], rec["pieces_awake"], rec["loadavg_before"][0], rec["loadavg_after"][0],
                  rec["other_cores"], " BUSY" if rec["busy"] else ""), flush=True)

    def stat(key):
        v = [r[key] for r in runs]
        return {"min": min(v), "median": statistics.median(v), "max": max(v)}

    keys = ("wall_s_per_simulated_s", "cpu_s_per_simulated_s", "ms_per_step", "steps_per_s",
            "cg_iterations_per_step", "pieces_awake")
    out = {"benchmark": "time_to_solution_baseline", "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
           "scene": "forty", "scale": 1.0, "material": "Table 1 (E 5e8 Pa, nu 0.4, rho 700, viscosity 2.5e5 Pa s)",
           "frictionPiece": a.friction, "threads": a.threads,
           "viscous": "implicit (warm-started PCG, %s preconditioner)" % a.preconditioner,
           "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "(libgomp default)"),
           "particle_radius_m": qdem.QdemMat().radius / table1Scale(),
           "table1_scale": table1Scale(), "tets": w.core.nTets, "pieces": w.core.nPieces, "dt": dt,
           "stable_dt_implicit": w.stableDt()["combinedImplicit"],
           "checkpoint": {"path": path, "t_s": None,
                          "rook_hit_s": float(extra["hit_s"]), "steps_from_setup": int(extra["steps"]),
                          "times_from": "the set-up: the king placed --gap from the rook, turned about its "
                                        "base's front edge with the angular velocity of its fall",
                          "king_angle_deg": float(extra["king_angle_deg"]), "gap_m": float(extra["gap_m"]),
                          "wall_s_to_make": float(extra["wall_s"]),
                          "held": "pieces %d-40 held (dynamic = False) ahead of the front: the cost of sleeping "
                                  "pieces" % (HELD_FROM + 1)},
           "steps": a.steps, "rounds": a.rounds, "busy_rule": BUSY_RULE, "host": host(),
           "summary": {k: stat(k) for k in keys}, "runs": runs}
    w.core.loadState(state)
    out["checkpoint"]["t_s"] = float(w.core.time)
    os.makedirs(os.path.dirname(a.log) or ".", exist_ok=True)
    with open(a.log, "w") as f:
        json.dump(out, f, indent=1)
    s = out["summary"]
    print("baseline: %d tets, dt %.4g s: wall s per simulated s min %.0f median %.0f (CPU %.0f / %.0f); "
          "%.0f steps/s; %.1f CG its/step; %d awake -> %s" % (
              out["tets"], dt, s["wall_s_per_simulated_s"]["min"], s["wall_s_per_simulated_s"]["median"],
              s["cpu_s_per_simulated_s"]["min"], s["cpu_s_per_simulated_s"]["median"], s["steps_per_s"]["median"],
              s["cg_iterations_per_step"]["median"], s["pieces_awake"]["median"], a.log))


if __name__ == "__main__":
    main()
