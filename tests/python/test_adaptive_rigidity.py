"""Adaptive rigidity (QdemEngine.rigidify; doc/formulation.md "Adaptive
rigidity"): a piece slow to deform moves as a rigid body in its current shape
until the load on it changes.

* A block resting on the floor becomes rigid, keeps its sag (its shape is
  the deformed one, to rounding) and presses on the floor with its weight.
* A block sliding into a rigid resting block wakes it (back to deformable):
  the velocities after the hit, the momentum and the energy ledger match the
  all-deformable run.
* A free tumbling rigid piece conserves its angular momentum and energy, and
  its nodes' kinetic energy is the rigid body's.
* The switch back to deformable is continuous: positions and velocities
  unchanged, no energy created.
* A rigid piece survives saveState / loadState (the run goes on with the
  same bits), and 1 and 2 threads give the same bits."""
import numpy as np
import pytest

import qdem
from qdem import _core
from conftest import rubber, totalEnergy

MAT = dict(radius=2e-3, viscosity=2000.0, frictionWall=0.0, frictionPiece=0.3)
G = 9.81


def _floor(w):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))


def _block(w, mat, x=0.0, vel=(0, 0, 0)):
    return w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(x, 0, 0.05 + mat.radius), vel=vel)


def _world(rigid, gravity=G, energy=False, rate=0.05, dwell=0.01, wake=0.1):
    w = qdem.World()
    w.core.gravity = (0, 0, -gravity)
    w.core.trackEnergy = energy
    w.core.rigidify = rigid
    w.core.rigidStrainRate = rate
    w.core.rigidTime = dwell
    w.core.rigidWakeLoad = wake
    return w


def _dt(w):
    return 0.8 * w.stableDt()["combined"]


def _stepUntil(w, dt, cond, limit, chunk=50):
    for _ in range(limit):
        w.core.step(dt, chunk)
        if cond():
            return True
    return False


def _height(b):
    z = b._nodes("pos")[:, 2]
    return z.max() - z.min()


def test_resting_block_becomes_rigid_keeps_its_sag_and_carries_its_weight():
    w = _world(True, energy=True)
    b = _block(w, rubber(**MAT))
    _floor(w)
    dt = _dt(w)
    # Settled first: dropped from its contact distance it bounces as a whole
    # on the floor's contact for ~0.1 s, a rigid motion whose load swings by
    # +-15 %: made rigid then, it deforms again when the swing exceeds rigidWakeLoad.
    w.core.rigidify = False
    w.core.step(dt, int(0.2 / dt))
    w.core.rigidify = True
    assert _stepUntil(w, dt, lambda: b.rigid, 400), "a block at rest on the floor must become rigid"
    assert w.core.nRigid == 1 and w.core.rigidSwitches == 1
    # Its shape is the sagged one: relative node positions kept to rounding
    # while it rests (a rigid motion only), and shorter than unloaded.
    c = b._nodes("pos").mean(axis=0)
    rel = b._nodes("pos") - c
    h = _height(b)
    e0 = w.core.energy["total"]
    w.core.step(dt, 2000)
    assert b.rigid and w.core.rigidSwitches == 1, "nothing changed its load: it stays rigid"
    # (it may rock a little on the floor's contacts: compare the shape, not the orientation)
    rel2 = b._nodes("pos") - b._nodes("pos").mean(axis=0)
    assert np.abs(rel2 @ rel2.T - rel @ rel.T).max() < 1e-15
    sag = 0.1 - h
    assert sag > 0
    # The same sag as the deformable block resting there.
    wd = _world(False)
    bd = _block(wd, rubber(**MAT))
    _floor(wd)
    wd.core.step(dt, int(round(w.core.time / dt)))
    assert 0.1 - _height(bd) == pytest.approx(sag, rel=0.02)
    # It presses on the floor with its weight, and the ledger stays balanced.
    fz = -w.core.obstacleReactions()[0][2]
    assert fz == pytest.approx(b.totalMass * G, rel=0.01)
    e = w.core.energy
    assert abs(e["total"] - e0) < 1e-6 * b.totalMass * G * 0.05
    assert 0 <= e["rigid"] < 1e-6 * b.totalMass * G * 0.05      # deformation energy removed at the switch: tiny
    assert e["elastic"] > 0                                      # the sag's strain energy stays booked


def _slidingIntoResting(rigid, energy=False):
    """Block A sliding at 1 m/s on a frictionless floor into block B resting 0.3 m ahead."""
    w = _world(rigid, energy=energy)
    mat = rubber(**MAT)
    a = _block(w, mat, x=-0.3, vel=(1.0, 0, 0))
    b = _block(w, mat, x=0.0)
    _floor(w)
    return w, a, b, _dt(w)


def _collision(rigid, energy=False):
    w, a, b, dt = _slidingIntoResting(rigid, energy)
    w.core.step(dt, 1)
    e0 = w.core.energy["total"]
    states = []
    while w.core.time < 0.32:
        w.core.step(dt, 20)
        p = np.asarray(a.momentum) + np.asarray(b.momentum)
        states.append((w.core.time, b.rigid, b.velocity[0], a.velocity[0], p[0], w.core.energy["total"]))
    return w, states, e0, (a, b)


def test_hit_wakes_a_rigid_block_and_the_collision_matches_the_deformable_one():
    _, soft, es0, _ = _collision(False, energy=True)
    w, rig, er0, (a, b) = _collision(True, energy=True)
    assert any(s[1] for s in rig if s[0] < 0.15), "the block standing still must be rigid before it is hit"
    assert not rig[-1][1] or w.core.rigidSwitches >= 2, "the hit must make it deformable"
    assert w.core.rigidSwitches >= 2
    # A reaches B at about 0.2 s; compare after the hit.
    after = [(s, r) for s, r in zip(soft, rig) if s[0] > 0.25]
    assert after and max(abs(s[2] - r[2]) for s, r in after) < 0.02   # B's velocity, 2 % of 1 m/s
    assert max(abs(s[3] - r[3]) for s, r in after) < 0.02              # A's
    assert max(s[2] for s, _ in after) > 0.3                            # B was really pushed
    m = a.totalMass
    assert max(abs(s[4] - r[4]) for s, r in after) < 1e-3 * m * 1.0     # momentum (frictionless floor: kept)
    # Energy: the ledger balanced as well as the deformable run's.
    scale = 0.5 * m * 1.0 ** 2
    driftSoft = max(abs(s[5] - es0) for s in soft)
    driftRig = max(abs(r[5] - er0) for r in rig)
    assert driftRig < max(2 * driftSoft, 1e-3 * scale), (driftRig, driftSoft)
    assert w.core.energy["rigid"] < 1e-3 * scale


def _spinning(wakeLoad=1e9):
    """A free brick (no gravity, no obstacle) tumbling about an axis near its intermediate one."""
    w = _world(True, gravity=0.0, energy=True, rate=10.0, dwell=0.0, wake=wakeLoad)
    mat = rubber(radius=2e-3, viscosity=50.0, young=2e7)
    b = w.addPiece(qdem.boxMesh((0.12, 0.06, 0.03), (4, 2, 1)), mat)
    omega = np.array([0.3, 20.0, 0.5])
    r = b._nodes("pos") - b._nodes("pos").mean(axis=0)
    b.vel[:] = np.cross(omega, r)
    return w, b, _dt(w)


def _nodeAngularMomentum(b, dt):
    """About the centre, with the positions at the half step of the velocities."""
    x = b._nodes("pos") - 0.5 * dt * b._nodes("vel")
    c = (x * b.mass[:, None]).sum(axis=0) / b.mass.sum()
    return (np.cross(x - c, b._nodes("vel")) * b.mass[:, None]).sum(axis=0)


def test_free_tumbling_rigid_piece_conserves_angular_momentum_and_energy():
    w, b, dt = _spinning()
    w.core.step(dt, 2)
    assert b.rigid
    L0 = _nodeAngularMomentum(b, dt)
    e0 = w.core.energy["total"]
    ek0 = w.core.energy["kinetic"]
    worst = 0.0
    for _ in range(40):
        w.core.step(dt, 100)
        worst = max(worst, np.linalg.norm(_nodeAngularMomentum(b, dt) - L0) / np.linalg.norm(L0))
        nodesKe = 0.5 * (b.mass[:, None] * b._nodes("vel") ** 2).sum()
        assert nodesKe == pytest.approx(w.core.energy["kinetic"], rel=1e-3)   # (half step against integer level)
    assert b.rigid
    assert worst < 1e-6, worst
    assert abs(w.core.energy["total"] - e0) < 1e-6 * ek0
    assert w.core.rigidSwitches == 1


def test_switch_back_to_deformable_is_continuous():
    """Made deformable from outside (rigidify switched off), the piece goes on
    from its rigid positions and velocities: nothing jumps, no energy appears."""
    w, b, dt = _spinning()
    w.core.step(dt, 50)
    assert b.rigid
    x, v = b._nodes("pos").copy(), b._nodes("vel").copy()
    e = dict(w.core.energy)
    w.core.rigidify = False
    w.core.step(dt, 1)            # the last rigid step; the sleep phase switches it
    assert not b.rigid and w.core.rigidSwitches == 2
    x1, v1 = b._nodes("pos").copy(), b._nodes("vel").copy()
    assert np.abs(x1 - x).max() < 2 * dt * np.abs(v).max()
    w.core.step(dt, 1)            # the first deformable step, from the rigid state
    x2, v2 = b._nodes("pos"), b._nodes("vel")
    # A leapfrog step from a rigid motion: the elastic forces of the frozen
    # shape are those it was in equilibrium with (none here but the
    # centrifugal stretch), so the velocities change by O(dt) only.
    assert np.abs(v2 - v1).max() < 1e-3 * np.abs(v1).max()
    assert np.abs(x2 - x1 - dt * v2).max() < 1e-15
    total = w.core.energy["total"]
    assert abs(total - e["total"]) < 1e-6 * e["kinetic"]


def test_rigid_state_survives_save_and_load(tmp_path):
    w = _world(True)
    b = _block(w, rubber(**MAT))
    _floor(w)
    dt = _dt(w)
    assert _stepUntil(w, dt, lambda: b.rigid, 400)
    path = str(tmp_path / "rigid.state")
    qdem.saveState(path, world=w)
    w.core.step(dt, 300)
    ref = np.array(w.core.pos, copy=True), np.array(w.core.vel, copy=True), w.core.rigidSwitches
    w2 = _world(True)
    b2 = _block(w2, rubber(**MAT))
    _floor(w2)
    qdem.loadState(path, world=w2)
    assert b2.rigid and w2.core.nRigid == 1 and w2.core.rigidSwitches == 1
    w2.core.step(dt, 300)
    assert np.array_equal(np.asarray(w2.core.pos), ref[0])
    assert np.array_equal(np.asarray(w2.core.vel), ref[1])
    assert w2.core.rigidSwitches == ref[2]


def test_one_and_two_threads_give_the_same_bits():
    out = []
    for n in (1, 2):
        _core.setThreads(n)
        try:
            w, a, b, dt = _slidingIntoResting(True)
            w.core.step(dt, 6000)
            out.append((np.array(w.core.pos, copy=True), np.array(w.core.vel, copy=True), w.core.rigidSwitches))
        finally:
            _core.setThreads(0)
    assert out[0][2] == out[1][2] and out[0][2] >= 1
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
