"""The contact-free scene on P = 1..4 ranks of this machine (doc/parallel_scaling.md,
"Benchmark").  The driver (default) starts `mpiexec -n P` on this same file
with --worker, one run per P, with a timeout, OMP_NUM_THREADS=1 and passive
waits (OMPI_MCA_mpi_yield_when_idle=1), and writes one JSON of every run:

    python3 run_ranks.py --build build --out out/bench/mpi_ranks.json

Per rank: owned nodes and tets, ghosts, neighbours, halo bytes and messages
sent per step (counted by the core: Domain::stepBytes), seconds per phase
(min and median over the timed steps), exchange seconds, step seconds, peak
memory.  Per run: the load average before and after, and max |dx| of the end
state against the P = 1 run (the split must not change the physics).  The
machine has 2 cores shared with others: P = 3, 4 are oversubscribed, so the
times are reported, not judged.

The worker also leaves the partition (node owners) and the mesh in an .npz
beside the JSON: model.py predicts each rank's bytes and messages from it."""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def buildScene(qdem, scale):
    """Four pieces of other sizes and orientations (~36k tets at scale 1)
    above a floor, the lowest one resting on it; contacts between pieces off
    (not distributed yet), so they must never touch: they are far apart."""
    from qdem import _core
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5,
                       frictionWall=0.4)
    stiff = qdem.QdemMat(young=8e6, poisson=0.25, density=1500.0, viscosity=0.0, radius=0.004, restitution=0.3,
                         frictionWall=0.6)
    s = scale
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.4, 0.2, 0.16), (20 * s, 10 * s, 8 * s)), mat, pos=(0, 0, 0.085), vel=(0.3, 0, 0))
    w.addPiece(qdem.boxMesh((0.24, 0.24, 0.24), (12 * s, 12 * s, 12 * s)), stiff, pos=(0.7, 0.1, 0.4),
               ori=((1, 1, 0), 0.6), angVel=(0, 0, 3.0))
    w.addPiece(qdem.boxMesh((0.32, 0.24, 0.16), (16 * s, 12 * s, 8 * s)), mat, pos=(-0.7, 0.3, 0.5),
               ori=((0, 1, 1), 1.1), vel=(0, -0.2, -0.5))
    w.addPiece(qdem.boxMesh((0.48, 0.16, 0.12), (24 * s, 8 * s, 6 * s)), stiff, pos=(0.0, -0.7, 0.3))
    c = w.core
    c.pointPolygonOn = False
    c.edgeEdgeOn = False
    c.gravity = (0, 0, -9.81)
    c.trackEnergy = True
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1  # a floor at z = 0 (YADE's Wall along z)
    o.young, o.friction = 1e8, 0.5
    c.setObstacles([o])
    return w


def stats(values):
    v = sorted(values)
    return {"min": v[0], "median": v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])}


def worker(a):
    import numpy as np
    from mpi4py import MPI

    import qdem
    comm = MPI.COMM_WORLD
    rssImport = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    w = buildScene(qdem, a.scale)
    c = w.core
    rssScene = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    if comm.size > 1:
        c.setCommunicator(comm)
    dt = 0.8 * w.stableDt()["combined"]  # from the replicated set-up: the same on every rank
    c.step(dt, a.warmup)  # the first step splits the world
    phases, stepS, exchS = {}, [], []
    for _ in range(a.steps):
        t0 = time.perf_counter()
        c.step(dt, 1)
        stepS.append(time.perf_counter() - t0)
        for k, v in c.timings.items():
            phases.setdefault(k, []).append(v)
        ps = c.partitionStats
        exchS.append(ps.get("exchangeSeconds", 0.0))
    ps = dict(c.partitionStats)
    mine = {"rank": comm.rank, "ownedNodes": int(ps.get("ownedNodes", c.nNodes)),
            "ownedTets": int(ps.get("ownedTets", c.nTets)), "ghosts": int(ps.get("ghosts", 0)),
            "neighbours": [int(n) for n in ps.get("neighbours", [])], "imbalance": float(ps.get("imbalance", 1.0)),
            "stepBytes": int(ps.get("stepBytes", 0)), "stepMessages": int(ps.get("stepMessages", 0)),
            "exchangeSeconds": stats(exchS), "stepSeconds": stats(stepS),
            "phaseSeconds": {k: stats(v) for k, v in phases.items()},
            "maxRssKB": {"afterImport": rssImport, "afterScene": rssScene,
                         "end": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}}
    owner = np.array(c.nodeOwner, copy=True)
    c.gatherAll()
    ranks = comm.gather(mine, root=0)
    if comm.rank == 0:
        np.savez_compressed(a.npz, nodeOwner=owner, tets=np.array(c.tets, copy=True),
                            pos=np.array(c.pos, copy=True), P=comm.size)
        with open(a.out, "w") as f:
            json.dump({"P": comm.size, "nodes": int(c.nNodes), "tets": int(c.nTets), "pieces": int(c.nPieces),
                       "dt": dt, "warmupSteps": a.warmup, "timedSteps": a.steps, "ranks": ranks}, f, indent=1)


def driver(a):
    import numpy as np
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_mpi_yield_when_idle="1",
               PYTHONPATH=os.path.abspath(os.path.join(a.build, "python")))
    runDir = os.path.join(os.path.dirname(a.out) or ".", "mpi_runs")
    os.makedirs(runDir, exist_ok=True)
    runs = []
    for P in range(1, a.max_ranks + 1):
        out, npz = os.path.join(runDir, "P%d.json" % P), os.path.join(runDir, "P%d.npz" % P)
        for f in (out, npz):
            if os.path.exists(f):
                os.remove(f)
        cmd = ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(P), sys.executable,
               os.path.abspath(__file__), "--worker", "--steps", str(a.steps), "--warmup", str(a.warmup),
               "--scale", str(a.scale), "--out", out, "--npz", npz]
        load0, t0 = os.getloadavg(), time.time()
        r = subprocess.run(cmd, env=env, timeout=a.timeout, capture_output=True, text=True)
        wall, load1 = time.time() - t0, os.getloadavg()
        if r.returncode != 0 or not os.path.exists(out):
            sys.stderr.write(r.stdout + r.stderr)
            raise SystemExit("run_ranks: P=%d failed (exit %d)" % (P, r.returncode))
        with open(out) as f:
            run = json.load(f)
        run.update({"loadAverageBefore": load0, "loadAverageAfter": load1, "wallSeconds": wall,
                    "npz": os.path.relpath(npz, os.path.dirname(a.out) or "."), "command": " ".join(cmd[:6])})
        runs.append(run)
        print("run_ranks: P=%d  %d tets, step median %.2f ms (rank max), exchange median %.2f ms, imbalance %.4f, "
              "bytes/step %s, load %.2f -> %.2f, %.1f s"
              % (P, run["tets"], 1e3 * max(x["stepSeconds"]["median"] for x in run["ranks"]),
                 1e3 * max(x["exchangeSeconds"]["median"] for x in run["ranks"]), run["ranks"][0]["imbalance"],
                 [x["stepBytes"] for x in run["ranks"]], load0[0], load1[0], wall), flush=True)
    # The split must not change the physics: end positions against P = 1.
    ref = np.load(os.path.join(runDir, "P1.npz"))["pos"]
    for run in runs:
        pos = np.load(os.path.join(os.path.dirname(a.out) or ".", run["npz"]))["pos"]
        run["maxAbsDxVsP1"] = float(np.max(np.abs(pos - ref)))
    res = {"what": "contact-free scene (4 pieces, gravity, a floor; contacts between pieces off) on P ranks of this "
                   "2-core machine shared with other jobs; P > 2 oversubscribed: times reported, not judged",
           "env": {"OMP_NUM_THREADS": "1", "OMPI_MCA_mpi_yield_when_idle": "1"},
           "notes": "per rank: stepBytes and stepMessages are what the rank sent in the last step (counted by the "
                    "core); times are min and median over the timed steps; phaseSeconds from World.timings; "
                    "exchangeSeconds = halo exchanges + the end-of-step gather; maxRssKB = peak resident memory",
           "runs": runs}
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
    print("run_ranks: wrote", a.out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="out/bench/mpi_ranks.json")
    ap.add_argument("--npz", default=None)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--warmup", type=int, default=10)
    ap.add_argument("--scale", type=int, default=1)
    ap.add_argument("--max-ranks", type=int, default=4)
    ap.add_argument("--timeout", type=float, default=150)
    a = ap.parse_args()
    if a.worker:
        worker(a)
    else:
        driver(a)


if __name__ == "__main__":
    main()
