"""A given thread count gives the same bits, contacts included: the same
script run twice (a parameter sweep with yade-batch, a re-run of a scene) at 2
QDEM threads gives bit-identical forces, positions, velocities and energy
ledger.  Point-polygon, edge-edge and sphere contacts add to per-thread force
buffers summed in thread order; each node (sphere) must therefore go to the
same thread every step and every run (static chunks).  With dynamic chunks a
node under another piece's corner took its reactions in one buffer or the
other by the threads' timing, and its force came out 1 ulp apart from the
first contact step (then amplified by the dynamics to ~1e-6 m)."""
import sys
from pathlib import Path

import numpy as np

import qdem
from qdem import _core

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "mpi"))
import scenes  # noqa: E402  (tests/mpi/scenes.py: the MPI tests' scenes)


def _slabAndCube():
    """A frictionless cube falling onto a moving slab: its corners press on
    the slab's top triangles (point-polygon reactions on the slab's nodes)."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5,
                       frictionWall=0.0, frictionPiece=0.0)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.4, 0.2, 0.04), (10, 5, 1)), mat, pos=(0, 0, 0.024), vel=(0.3, 0, -0.2))
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.1, 0.05, 0.044 + 0.008 + 0.025 - 0.0005),
               vel=(0, 0, -0.5))
    return w


def _state(w):
    c = w.core
    return [np.array(c.force, copy=True), np.array(c.pos, copy=True), np.array(c.vel, copy=True)]


def _firstDifference(a, b):
    """None when the arrays are bit-identical, else (name, row, |difference|)."""
    for name, x, y in zip(("force", "pos", "vel"), a, b):
        if not np.array_equal(x, y):
            d = np.abs(x - y).max(axis=1)
            i = int(np.argmax(d))
            return name, i, float(d[i])
    return None


def test_two_worlds_stepped_in_turn_give_the_same_bits_at_two_threads():
    """Two identical worlds stepped in turn in one process (what a script
    comparing two set-ups does): their forces and positions agree bit for bit
    every step (dynamic chunks: 1.8e-15 N apart at slab nodes 82 and 84 from
    step 1 in 5 trials of 6)."""
    _core.setThreads(2)
    for trial in range(3):
        ws = [_slabAndCube() for _ in range(2)]
        dt = 0.5 * ws[0].stableDt()["combined"]
        touched = 0
        for step in range(60):
            for w in ws:
                w.core.step(dt, 1)
            touched += ws[0].core.contactCounts["pointPolygon"]
            diff = _firstDifference(_state(ws[0]), _state(ws[1]))
            assert diff is None, f"trial {trial}, step {step + 1}: {diff[0]} of row {diff[1]} differs by {diff[2]:.3g}"
        assert touched > 0, "the cube must touch the slab"


def test_two_runs_of_a_contact_scene_give_the_same_bits_at_two_threads():
    """One after the other, two runs of a scene with point-polygon and edge-edge
    contacts between pieces, friction, a floor, gravity, Cundall damping and
    the energy ledger: same bits at the end."""
    _core.setThreads(2)

    def run():
        w = scenes.withContacts()
        w.core.localDamping = 0.2
        dt = 0.5 * w.stableDt()["combined"]
        counts = {"pointPolygon": 0, "edgeEdge": 0}
        for _ in range(40):
            w.core.step(dt, 25)
            for k in counts:
                counts[k] += w.core.contactCounts[k]
        return _state(w), dict(w.core.energy), counts

    (s1, e1, n1), (s2, e2, n2) = run(), run()
    assert n1["pointPolygon"] > 0 and n1["edgeEdge"] > 0, n1
    assert n1 == n2
    diff = _firstDifference(s1, s2)
    assert diff is None, f"{diff[0]} of row {diff[1]} differs by {diff[2]:.3g}"
    assert e1 == e2


def test_two_runs_with_yade_spheres_give_the_same_bits_at_two_threads(scene):
    """A YADE scene: spheres dropped onto a slab resting on a wall, twice: the
    spheres' and the slab's positions agree bit for bit.  (A guard of the
    sphere path: with dynamic chunks in the sphere loop this scene still gave
    the same bits, unlike the two above.)"""
    from yade import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                      Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                      Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator,
                      Vector3, utils)
    O = scene

    def run():
        O.reset()
        qdem.reset()
        _core.setThreads(2)
        mat = qdem.QdemMat(young=1e7, poisson=0.3, density=2000.0, viscosity=0.0, radius=0.002, restitution=0.5,
                           frictionWall=0.4, frictionPiece=0.4)
        slab = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.04), (8, 8, 2)), mat, pos=(0, 0, 0.022))
        O.bodies.append(utils.wall(0, axis=2, sense=1))
        fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.4, density=1000))
        ids = []
        for i in range(4):
            for j in range(4):
                x, y = -0.06 + 0.04 * i, -0.06 + 0.04 * j
                ids.append(O.bodies.append(utils.sphere((x, y, 0.0525 + 0.0004 * (i + j)), 0.008, material=fm)))
                O.bodies[ids[-1]].state.vel = Vector3(0.1 * (i - 1.5), 0.05 * (j - 1.5), -0.5)
        O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
                     InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                                     [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
                     qdem.QdemEngine(damping=0.1), NewtonIntegrator(gravity=(0, 0, -9.81), damping=0.1)]
        O.dt = 0.3 * O.engines[3].stableDt()["combined"]
        touched = 0
        for _ in range(300):
            O.step()
            touched += O.engines[3].world.core.contactCounts["sphere"]
        spheres = np.array([list(O.bodies[i].state.pos) + list(O.bodies[i].state.vel) for i in ids])
        return touched, spheres, np.array(slab.pos, copy=True), np.array(O.engines[3].world.core.force, copy=True)

    t1, sp1, p1, f1 = run()
    t2, sp2, p2, f2 = run()
    assert t1 > 0, "the spheres must touch the slab"
    assert t1 == t2
    assert np.array_equal(sp1, sp2), np.abs(sp1 - sp2).max()
    assert np.array_equal(p1, p2), np.abs(p1 - p2).max()
    assert np.array_equal(f1, f2), np.abs(f1 - f2).max()
