"""The bench scenes of compare_builds.py, one per process: run one scene with
whichever qdem package is first on PYTHONPATH and write node positions (and
YADE sphere positions, obstacle reactions, contact counts) at a few
checkpoints to an .npz file.  Only the public Python API that the builds
before and after the World restructuring share is used.

Core-only scenes (cubes27, shogi, restart) run in plain Python:
    PYTHONPATH=<build>/python /usr/bin/python3.11 scripts/arch/scenes.py --scene cubes27 --threads 1 --out a.npz
the YADE one (spheres) inside YADE:
    PYTHONPATH=<build>/python yade -j 1 -n -x scripts/arch/scenes.py --scene spheres --threads 1 --out a.npz

Written keys: iters (K,) checkpoint iterations; pos (K, n, 3) positions
(QDEM nodes, then YADE spheres); ref (n, 3) positions at iteration 0;
force (K, m) obstacle reactions (QDEM's on each obstacle; for spheres also
YADE's total force on the floor); counts (JSON: largest contact counts seen
at the end of any chunk of steps, Verlet rebuilds, ...); meta (JSON)."""
import argparse
import json
import math
import sys
import time

import numpy as np

import qdem
from qdem import _core

CHUNK = 50          # steps between samples of the contact counts


def floor(core, young=0.0, friction=None):
    """A fixed one-sided wall at z = 0 facing +z (as scripts/bench/benchutil.py) and gravity."""
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense, o.young = 0, 0, 2, 1, young
    if friction is not None:
        o.friction = friction
    core.setObstacles([o])
    core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    core.gravity = (0, 0, -9.80665)


class Recorder:
    """Steps a scene to each checkpoint, sampling contact counts on the way."""

    def __init__(self, core, step, positions=None, forces=None):
        self.core, self.step = core, step
        self.positions = positions or (lambda: np.array(core.pos))
        self.forces = forces or (lambda: np.array(core.obstacleReactions()[:, :3]).ravel())
        self.iters, self.pos, self.force = [], [], []
        self.counts = {}
        self.ref = self.positions().copy()
        self.rebuilds0 = core.verletRebuilds

    def sample(self):
        for k, v in self.core.contactCounts.items():
            self.counts[k] = max(self.counts.get(k, 0), int(v))

    def run(self, checkpoints):
        for target in checkpoints:
            while self.core.iter < target:
                self.step(min(CHUNK, target - self.core.iter))
                self.sample()
            self.iters.append(int(self.core.iter))
            self.pos.append(self.positions().copy())
            self.force.append(self.forces().copy())

    def save(self, path, **meta):
        counts = dict(self.counts, verletRebuilds=int(self.core.verletRebuilds - self.rebuilds0))
        for k in ("nAsleep", "wakeCount"):
            if hasattr(self.core, k):
                counts[k] = int(getattr(self.core, k))
        meta = dict(meta, nNodes=int(self.core.nNodes), nTets=int(self.core.nTets), threads=_core.getThreads())
        np.savez(path, iters=np.array(self.iters), pos=np.array(self.pos), ref=self.ref, force=np.array(self.force),
                 counts=json.dumps(counts), meta=json.dumps(meta))


def checkpoints(start, steps, n):
    """n checkpoint iterations evenly spread over (start, start + steps]."""
    return [start + int(round(steps * (k + 1) / n)) for k in range(n)]


def coreStepper(world, dt):
    return lambda n: world.core.step(dt, n)


# --- (a) 27 cubes on a floor ---------------------------------------------------------------------------------

def cubes27World(cells):
    """The thrown 27-cube stack of cubes27() with `cells`^3 cells of 12 tets
    per cube, its floor, and dt = 0.8 x its stable step."""
    mat = qdem.QdemMat()
    r, L = mat.radius, 4.0
    w = qdem.World()
    cube = qdem.boxMesh((L, L, L), (cells,) * 3, tetsPerCell=12)
    gap = 2 * r - 0.002
    rng = np.random.RandomState(3)
    for i in range(3):
        for j in range(3):
            for k in range(3):
                w.addPiece(cube, mat, pos=(i * (L + gap), j * (L + gap), L / 2 + r - 0.001 + k * (L + gap)),
                           vel=tuple(rng.uniform(-1, 1, 3)), angVel=tuple(rng.uniform(-0.2, 0.2, 3)))
    floor(w.core)
    return w, 0.8 * w.stableDt()["combined"]


def cubes27(a):
    """scripts/bench/bench_cubes27.py's stack (3x3x3 cubes of edge 4 m, seed
    Table 1 material, neighbours overlapping by 2 mm), at a{cells}^3 cells of
    12 tets per cube instead of 8^3 so that a thousand steps take seconds; each
    cube is thrown with its own velocity (up to 1 m/s) and spin, so the stack
    moves: faces slide and part, edge-edge contacts come and go and the Verlet
    lists are rebuilt.  dt = 0.8 x the stable step (the coarse mesh allows 4x
    Table 1's 6.4e-6 s)."""
    w, dt = cubes27World(a.cells)
    rec = Recorder(w.core, coreStepper(w, dt))
    rec.run(checkpoints(0, a.steps, a.checkpoints))
    return rec, dict(dt=dt)


# --- (b) shogi: two rooks ------------------------------------------------------------------------------------

def shogi(a):
    """Seed Figure 7: a rook tipped over onto a second one (qdem.shogi's two_rooks
    line, spacing 0.8 heights), scripts/shogi/domino.py's 'soft' material (E
    1 MPa, real size: dt ~7e-6 s) on a floor wall.  The first piece hits the
    second at about step 7,000 and the second starts to topple; the default
    10,000 steps run through the hit.  The rook mesh is read from --mesh (made
    once by CGAL, so both builds start from the same nodes)."""
    from qdem.scenes import shogi as sh
    m = np.load(a.mesh)
    rook = qdem.Mesh(m["nodes"], m["tets"])
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4, frictionPiece=0.1,
                       frictionWall=0.5)
    H = sh.KINDS["rook"][0] * 1e-3
    push = math.sqrt(9.81 / H)                   # as shogi.scene
    w = qdem.World()
    for i in range(2):
        w.addPiece(rook, mat, pos=(i * 0.8 * H, 0.0, mat.radius), ori=sh.STANDING,
                   angVel=(0.0, push, 0.0) if i == 0 else (0.0, 0.0, 0.0))
    floor(w.core, young=1e7, friction=0.5)
    dt = 0.8 * w.stableDt()["combined"]
    rec = Recorder(w.core, coreStepper(w, dt))
    rec.run(checkpoints(0, a.steps, a.checkpoints))
    return rec, dict(dt=dt)


def shogiMesh(path):
    """The rook mesh of qdem.shogi.mesh, saved for every run of the shogi scene."""
    from qdem.scenes import shogi as sh
    m = sh.mesh("rook")
    np.savez(path, nodes=m.nodes, tets=m.tets)


# --- (c) YADE spheres dropped on a QDEM block ----------------------------------------------------------------

def spheres(a):
    """scripts/bench/bench_spheres.py made small: a{spheres} YADE spheres (r 6 mm
    +-15 %) thrown down at 1 m/s from a cloud just above a QDEM block (0.12 m,
    6^3 cells) standing on a YADE floor wall, in a 0.2 m box.  Spheres hit the
    block from step ~150, bounce, pile up and press it onto the floor.  No
    damping (QDEM nodes and spheres alike)."""
    from yade import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                      Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                      Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, O, pack, utils)
    block, box = 0.12, 0.2
    O.reset()
    qdem.reset()
    mat = qdem.QdemMat(young=5e5, poisson=0.3, density=1000.0, viscosity=20.0, radius=0.002, frictionPiece=0.5)
    qdem.addPiece(qdem.boxMesh((block, block, block), (6, 6, 6)), mat, pos=(0, 0, block / 2 + mat.radius))
    wm = O.materials.append(FrictMat(young=1e7, frictionAngle=0.3, density=1000))
    floorId = O.bodies.append(utils.wall(0, axis=2, sense=1, material=wm))
    for ax in (0, 1):
        O.bodies.append(utils.wall(-box / 2, axis=ax, sense=1, material=wm))
        O.bodies.append(utils.wall(box / 2, axis=ax, sense=-1, material=wm))
    sm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.4, density=2500))
    sp = pack.SpherePack()
    sp.makeCloud((-box / 2, -box / 2, block + 0.01), (box / 2, box / 2, block + 0.08), rMean=0.006, rRelFuzz=0.15,
                 num=a.spheres, seed=7)
    ids = sp.toSimulation(material=sm)
    for i in ids:
        O.bodies[i].state.vel = (0, 0, -1.0)
    engine = qdem.QdemEngine(threads=a.threads)
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                                 [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
                 engine, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.0)]
    O.dt = min(0.5 * utils.PWaveTimeStep(), 0.5 * engine.stableDt()["combined"])
    core = qdem.defaultWorld().core

    def positions():
        return np.vstack([np.array(core.pos), np.array([tuple(O.bodies[i].state.pos) for i in ids])])

    def forces():
        # QDEM's reaction on each obstacle, then YADE's whole force on the floor (spheres included)
        return np.concatenate([np.array(core.obstacleReactions()[:, :3]).ravel(), np.array(tuple(O.forces.f(floorId)))])

    O.step()                                     # the engine hands the walls over to QDEM on its first step
    rec = Recorder(core, lambda n: O.run(n, True), positions, forces)
    rec.ref = positions().copy()
    rec.run(checkpoints(core.iter, a.steps, a.checkpoints))
    return rec, dict(dt=O.dt, spheres=len(ids))


# --- (d) a restart -------------------------------------------------------------------------------------------

def restartScene():
    """tests/python/test_restart.py's scene: a block slides into a stack of two
    that fall asleep meanwhile (sleeping on); friction, energy tracking.  The
    slider hits the stack at about step 11,000 and wakes it."""
    w = qdem.World()
    mat = qdem.QdemMat(young=1e7, poisson=0.3, density=1000.0, viscosity=2000.0, radius=2e-3, restitution=0.5,
                       frictionWall=0.0, frictionPiece=0.3)
    box = qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3))
    w.addPiece(box, mat, pos=(-0.3, 0, 0.052), vel=(1.0, 0, 0))
    w.addPiece(box, mat, pos=(0.0, 0.02, 0.052))
    w.addPiece(box, mat, pos=(0.0, 0.02, 0.156))
    floor(w.core)
    w.core.gravity = (0, 0, -9.81)
    w.core.trackEnergy = True
    w.core.sleepVelocity = 1e-3
    w.core.sleepTime = 0.01
    return w, 0.8 * w.stableDt()["combined"]


def restart(a):
    """--phase straight: N = a.restartAt steps, the state saved to a.state
    (qdem.saveState), then M = a.steps more; --phase resume: the scene built
    again in this fresh process, a.state loaded (qdem.loadState), M steps.
    Checkpoints are the same iterations in both (N + k M / K)."""
    w, dt = restartScene()
    if a.phase == "straight":
        ref = np.array(w.core.pos)
        w.core.step(dt, a.restartAt)
        qdem.saveState(a.state, world=w, label="compare_builds")
    else:
        ref = None
        extra = qdem.loadState(a.state, world=w)
        assert extra.get("label") == "compare_builds", extra
        assert w.core.iter == a.restartAt, (w.core.iter, a.restartAt)
    rec = Recorder(w.core, coreStepper(w, dt))
    if ref is not None:
        rec.ref = ref
    rec.run(checkpoints(a.restartAt, a.steps, a.checkpoints))
    return rec, dict(dt=dt, phase=a.phase)


SCENES = {"cubes27": cubes27, "shogi": shogi, "spheres": spheres, "restart": restart}
YADE_SCENES = {"spheres"}


def main(argv):
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", choices=sorted(SCENES) + ["shogi-mesh"], required=True)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--steps", type=int, required=False, default=1000)
    ap.add_argument("--checkpoints", type=int, default=5)
    ap.add_argument("--out", required=True)
    ap.add_argument("--cells", type=int, default=4, help="cubes27: cells per cube edge")
    ap.add_argument("--spheres", type=int, default=400)
    ap.add_argument("--mesh", help="shogi: rook mesh .npz")
    ap.add_argument("--phase", choices=["straight", "resume"], default="straight")
    ap.add_argument("--restartAt", type=int, default=11000)
    ap.add_argument("--state", help="restart: state file written (straight) or read (resume)")
    a = ap.parse_args(argv)
    if a.scene == "shogi-mesh":
        shogiMesh(a.out)
        return
    _core.setThreads(a.threads)
    t = time.perf_counter()
    rec, meta = SCENES[a.scene](a)
    wall = time.perf_counter() - t
    rec.save(a.out, wall=wall, scene=a.scene, qdem=qdem.__file__, **meta)
    print("scenes.py %s: %d threads, %d checkpoints, %.1f s, counts %s" % (a.scene, a.threads, len(rec.iters), wall,
                                                                          json.dumps(rec.counts)), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
