"""Sleeping pieces (doc/sleeping.md): a piece at rest is left out of the step
until something near it moves, and what the scene does is the same as without
sleeping to within the sleep velocity.

* A block resting on the floor falls asleep, stays exactly where it is, and
  still presses on the floor with its weight (frozen reaction).
* A block sliding into a sleeping block wakes it and pushes it as if it had
  been awake all along (velocities within 1 % of the sliding speed).
* Energy: the total is as well kept as without sleeping; only the kinetic
  energy zeroed at sleep (tiny) is booked as "sleep".
* Two stacked sleeping blocks skip their contact (none computed) and keep
  their elastic and contact energies.
* A moving obstacle, a write through Piece.vel or a change of gravity wakes
  a sleeping piece.
* A piece that is not dynamic (Piece.dynamic = False) stays where it is,
  whatever touches it, until it is made dynamic again; a block bouncing off it
  moves as off the same block with every node blocked."""
import numpy as np
import pytest

import qdem
from conftest import rubber

MAT = dict(radius=2e-3, viscosity=2000.0, frictionWall=0.0, frictionPiece=0.3)


def _floor(w, vz=0.0):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, vz, 0, 0, 0.0]]))


def _block(w, mat, x=0.0, z=None, vel=(0, 0, 0)):
    z = 0.05 + mat.radius if z is None else z
    return w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(x, 0, z), vel=vel)


def _world(sleep):
    w = qdem.World()
    w.core.gravity = (0, 0, -9.81)
    if sleep:
        w.core.sleepVelocity = 2e-4
        w.core.sleepTime = 0.01
    return w


def _dt(w):
    return 0.8 * w.stableDt()["combined"]


def _stepUntil(w, dt, cond, limit):
    for _ in range(limit):
        w.core.step(dt, 50)
        if cond():
            return True
    return False


def _sleepingBlock():
    """A block resting on the floor, stepped until it sleeps."""
    w = _world(True)
    b = _block(w, rubber(**MAT))
    _floor(w)
    dt = _dt(w)
    assert _stepUntil(w, dt, lambda: b.asleep, 400), "a block at rest on the floor must fall asleep"
    return w, b, dt


def test_block_at_rest_sleeps_stays_put_and_keeps_pressing_on_the_floor():
    w, b, dt = _sleepingBlock()
    assert w.core.nAsleep == 1 and w.core.sleepCount == 1
    x = b._nodes("pos").copy()
    weight = b.totalMass * 9.81
    w.core.step(dt, 500)
    assert np.array_equal(b._nodes("pos"), x)           # not integrated
    assert np.all(b._nodes("vel") == 0)
    fz = w.core.obstacleReactions()[0][2]
    assert -fz == pytest.approx(weight, rel=0.01)        # still pressing with its weight
    assert b.asleep
    b.vel[:] = 0.0                                       # a writable view handed out: awake
    assert not b.asleep and w.core.wakeCount == 1


def _slidingIntoStill(sleep, energy):
    """Block A sliding at 1 m/s towards block B standing still 0.3 m ahead."""
    w = _world(sleep)
    w.core.trackEnergy = energy
    mat = rubber(**MAT)
    a = _block(w, mat, x=-0.3, vel=(1.0, 0, 0))
    b = _block(w, mat, x=0.0)
    _floor(w)
    return w, a, b, _dt(w)


def _collision(sleep, energy=False):
    w, a, b, dt = _slidingIntoStill(sleep, energy)
    w.core.step(dt, 1)
    e0 = w.core.energy["total"]
    states = []
    while w.core.time < 0.32:
        w.core.step(dt, 20)
        states.append((w.core.time, b.asleep, b.velocity[0], a.velocity[0]))
    return w, states, e0


def test_collision_with_a_sleeping_block_is_the_same_as_awake():
    _, awake, _ = _collision(False)
    w, slept, _ = _collision(True)
    asleepBefore = [s[1] for s in slept if s[0] < 0.15]
    assert any(asleepBefore), "the block standing still must sleep before it is hit"
    assert not slept[-1][1], "the hit must wake it"
    assert w.core.wakeCount >= 1
    # The sliding block reaches B at about 0.2 s; compare after the hit.
    after = [(s0, s1) for s0, s1 in zip(awake, slept) if s0[0] > 0.25]
    assert after and max(abs(p[2] - q[2]) for p, q in after) < 0.01   # B's velocity, 1 % of 1 m/s
    assert max(abs(p[3] - q[3]) for p, q in after) < 0.01              # A's
    assert max(p[2] for p, _ in after) > 0.3                            # B was really pushed


def test_energy_is_kept_across_sleep_and_wake():
    w0, _, e00 = _collision(False, energy=True)
    w1, _, e10 = _collision(True, energy=True)
    drift0 = abs(w0.core.energy["total"] - e00)
    drift1 = abs(w1.core.energy["total"] - e10)
    ke0 = 0.5 * 1.0 ** 2 * w1.pieces[0].totalMass
    assert drift1 <= drift0 + 1e-4 * ke0
    assert 0 <= w1.core.energy["sleep"] < 1e-4 * ke0


def test_stacked_sleeping_blocks_skip_their_contact_and_keep_their_energy():
    w = _world(True)
    w.core.trackEnergy = True
    mat = rubber(**MAT)
    low = _block(w, mat)
    top = _block(w, mat, z=0.15 + 3 * mat.radius)  # faces 2 r apart: just touching
    _floor(w)
    dt = _dt(w)
    w.core.step(dt, 1)
    assert w.core.contactCounts["pointPolygon"] > 0
    assert _stepUntil(w, dt, lambda: low.asleep and top.asleep, 600)
    e = w.core.energy
    w.core.step(dt, 100)
    assert w.core.contactCounts["pointPolygon"] == 0 and w.core.contactCounts["edgeEdge"] == 0
    e2 = w.core.energy
    for k in ("elastic", "contactElastic", "kinetic"):
        assert e2[k] == e[k]
    assert e2["elastic"] > 0 and e2["contactElastic"] > 0
    fz = w.core.obstacleReactions()[0][2]
    assert -fz == pytest.approx((low.totalMass + top.totalMass) * 9.81, rel=0.01)


def test_moving_floor_and_gravity_change_wake_pieces():
    w, b, dt = _sleepingBlock()
    _floor(w, vz=0.01)                 # the same floor, now moving up
    w.core.step(dt, 1)
    assert not b.asleep
    w.core.step(dt, 200)
    assert not b.asleep                # never while the floor moves
    _floor(w)
    assert _stepUntil(w, dt, lambda: b.asleep, 400)
    w.core.gravity = (0, 0, -5.0)
    assert not b.asleep


def test_a_moving_piece_never_sleeps_even_with_zero_sleep_time():
    w = _world(True)
    w.core.sleepTime = 0.0
    mat = rubber(**MAT)
    b = _block(w, mat, z=0.5, vel=(0.5, 0, 0))    # in flight
    rest = _block(w, mat, x=1.0)                  # at rest on the floor
    _floor(w)
    dt = _dt(w)
    w.core.step(dt, 1)
    assert not b.asleep
    w.core.step(dt, 200)
    assert not b.asleep
    # The block at rest sleeps once the floor carries it; the one in flight not while it flies.
    assert _stepUntil(w, dt, lambda: rest.asleep, 400)
    assert b.centroid[2] > 0.2 and not b.asleep


def test_slow_is_not_at_rest_a_piece_in_the_air_or_driven_through_blocked_dofs_stays_awake():
    """A piece let go in the air is slower than sleepVelocity for sleepVelocity / g
    seconds, one at the top of a throw too, and one pulled slowly through blocked
    DOFs for good: each fell asleep (hanging in the air, the pull erased)."""
    w = _world(True)
    w.core.sleepVelocity = 0.3          # 0.3 / g = 31 ms > sleepTime (10 ms)
    mat = rubber(**MAT)
    hanging = _block(w, mat, z=1.0)
    thrown = _block(w, mat, x=1.0, z=1.0, vel=(0, 0, 0.5))
    _floor(w)
    dt = _dt(w)
    steps = int(0.2 / dt)
    w.core.step(dt, steps)
    t = steps * dt
    assert not hanging.asleep and not thrown.asleep
    assert hanging.centroid[2] == pytest.approx(1.0 - 0.5 * 9.81 * t * t, rel=1e-3)
    assert thrown.centroid[2] == pytest.approx(1.0 + 0.5 * t - 0.5 * 9.81 * t * t, rel=1e-3)
    # No gravity: a free block pulled at 5 mm/s on one face (sleepVelocity 1 cm/s).
    w = qdem.World()
    w.core.sleepVelocity, w.core.sleepTime = 0.01, 0.01
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), mat)
    face = np.asarray(p.pos)[:, 0] > 0.0499
    p.blocked[face] = 7
    p.vel[face] = (0.005, 0, 0)
    dt = _dt(w)
    steps = int(0.2 / dt)
    w.core.step(dt, steps)
    assert not p.asleep
    assert np.asarray(p.pos)[face, 0].mean() == pytest.approx(0.05 + 0.005 * steps * dt, rel=1e-6)
    assert p.centroid[0] > 0.0005   # the rest of the block follows


def test_sleeping_is_off_by_default_and_checks_its_settings():
    w = qdem.World()
    assert w.core.sleepVelocity == 0
    with pytest.raises(Exception, match="sleepVelocity"):
        w.core.sleepVelocity = -1.0
    with pytest.raises(Exception, match="sleepTime"):
        w.core.sleepTime = float("nan")
    with pytest.raises(ValueError, match="sleepVelocity"):
        qdem.QdemEngine(sleepVelocity=-1)


def test_engine_puts_a_block_on_a_yade_wall_to_sleep(scene):
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mat = rubber(**MAT)
    b = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.05 + mat.radius))
    wall = O.bodies.append(utils.wall(0, axis=2, sense=1))
    # 2e-4 m/s: the frozen reaction is within m w v of the weight (doc/sleeping.md);
    # at 1e-3 m/s it froze 1.4 % off once the contact springs took area weights.
    O.engines = [ForceResetter(), qdem.QdemEngine(sleepVelocity=2e-4, sleepTime=0.01),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.8 * qdem.stableDt()["combined"]
    O.trackEnergy = True
    for _ in range(400):
        O.run(50, True)
        if b.asleep:
            break
    assert b.asleep
    O.run(10, True)
    assert -O.forces.f(wall)[2] == pytest.approx(b.totalMass * 9.81, rel=0.01)
    assert "qdemSleep" in O.energy.keys()


# -- Piece.dynamic = False: held asleep where it is ---------------------------

def _hitFixedBlock(hold):
    """Block A slides into block B, which is fixed from step 200 on: held
    (dynamic = False) or every node blocked at zero velocity (the reference)."""
    w, a, b, dt = _slidingIntoStill(sleep=False, energy=True)   # holding works with sleeping off
    w.core.step(dt, 200)
    if hold:
        b.dynamic = False
    else:
        b.vel[:] = 0.0
        b.blocked[:] = 7
    e0 = w.core.energy["total"]
    history = []
    while w.core.time < 0.4:
        w.core.step(dt, 100)
        history.append(a.velocity[0])
    return w, a, b, np.array(history), e0


def test_a_piece_that_is_not_dynamic_stays_put_and_others_bounce_off_it():
    ref = _hitFixedBlock(hold=False)[3]
    w, a, b, held, e0 = _hitFixedBlock(hold=True)
    assert not b.dynamic and b.asleep and w.core.nAsleep == 1
    x = b._nodes("pos").copy()
    with pytest.raises(ValueError, match="read-only"):
        b.pos[:] = 0.0
    w.core.wakeAll()                       # nothing but dynamic = True wakes it
    w.core.step(_dt(w), 100)
    assert np.array_equal(b._nodes("pos"), x) and b.asleep
    # A bounces off B as off the same block with every node blocked.
    assert ref.min() < -0.3 and held[-1] < -0.3
    assert np.abs(held - ref).max() < 1e-3
    ke = 0.5 * a.totalMass * 1.0 ** 2
    assert abs(w.core.energy["total"] - e0) < 0.01 * ke   # the books stay balanced


def test_a_piece_held_in_the_air_falls_freely_once_dynamic_again(tmp_path):
    w = _world(True)
    mat = rubber(**MAT)
    b = _block(w, mat, z=1.0)
    b.dynamic = False
    dt = _dt(w)
    w.core.step(dt, 500)
    z0 = b.centroid[2]
    assert z0 == pytest.approx(1.0, abs=1e-12) and b.asleep
    path = str(tmp_path / "held.npz")       # kept across a restart
    qdem.saveState(path, world=w)
    w2 = _world(True)
    b2 = _block(w2, mat, z=1.0)
    qdem.loadState(path, world=w2)
    assert not b2.dynamic and b2.asleep
    b2.dynamic = True
    assert not b2.asleep
    t0 = w2.core.time
    w2.core.step(dt, 2000)
    t = w2.core.time - t0
    assert z0 - b2.centroid[2] == pytest.approx(0.5 * 9.81 * t * t, rel=0.01)
    with pytest.raises(Exception, match="piece"):
        w2.core.setDynamic(5, False)


@pytest.mark.parametrize("hold", [False, True])
def test_a_box_dropped_on_a_held_piece_rests_on_it(scene, hold):
    """YADE's Body.dynamic = False is a fixed body that others still hit.  A
    held piece touched obstacles only with its push at the hold: a dynamic
    YADE box dropped on a held block fell through it in free fall (z = -0.39
    m at t = 0.4 s), and a platen driven into it met no force.  Its contacts
    with obstacles are now computed every step: the box rests on it as on
    the free block, its weight carried (O.forces on the box = m g)."""
    from yade import ForceResetter, FrictMat, NewtonIntegrator, utils
    O = scene
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=10, radius=0.005)
    p = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.1), (2, 2, 2)), mat, pos=(0, 0, 0.055))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    bm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.3, density=1000))
    box = O.bodies.append(utils.box((0, 0, 0.25), (0.03, 0.03, 0.03), fixed=False, material=bm))
    engine = qdem.QdemEngine()
    O.engines = [ForceResetter(), engine, NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 0.5 * engine.stableTimeStep()
    O.run(20, True)
    if hold:
        p.dynamic = False
    top = p.pos[:, 2].max()
    O.run(int(1.2 / O.dt), True)                                           # it bounces for about 1 s
    b = O.bodies[box]
    assert b.state.pos[2] - top == pytest.approx(0.03 + 0.005, abs=1e-3)   # on the block, not through it
    assert abs(b.state.vel[2]) < 0.01
    assert O.forces.f(box)[2] == pytest.approx(b.state.mass * 9.81, rel=0.02)
    if hold:
        assert p.pos[:, 2].max() == top and p.asleep                       # the held block did not move


def test_writing_to_a_held_piece_names_the_piece_and_the_fix():
    """NumPy's bare "assignment destination is read-only" named neither the
    piece, nor why, nor dynamic = True."""
    w = _world(False)
    b = _block(w, rubber(**MAT), z=0.5)
    b.dynamic = False
    for name in ("pos", "vel", "extForce", "blocked"):
        with pytest.raises(ValueError, match=r"piece 0 is held \(dynamic = False\): its %s is read-only while it "
                                             r"is held.*Set piece.dynamic = True first" % name):
            getattr(b, name)[:] = 0
    with pytest.raises(ValueError, match=r"its vel is read-only"):
        b.vel[0] += 1.0
    with pytest.raises(ValueError, match=r"its pos is read-only"):
        b.pos[:, 2] *= 2
    b.dynamic = True
    b.vel[:] = 0.0                                                          # and writable again
