"""viscousIntegration='implicit': the semi-implicit Kelvin-Voigt update
(doc/formulation.md 2.1).  Damping of a mode against xi = beta*omega/2,
first-order agreement with the explicit scheme, stability beyond the explicit
viscous limit, exact momentum whatever the tolerance, blocked DOFs, sleeping
pieces, the energy ledger, threads, bad settings."""
import math

import numpy as np
import pytest

import qdem
import qdem.modes as modes
from conftest import rubber

IMPLICIT = 1


def _cube_mode(xi, cells=6):
    """A free cube of cells^3 (6 per cell) whose first elastic mode has damping ratio xi: world,
    piece, mode shape (per node), lumped masses, omega."""
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000.0, viscosity=0, radius=0.01)
    mesh = qdem.boxMesh((0.4, 0.4, 0.4), (cells,) * 3, tetsPerCell=6)
    mat.viscosity = modes.viscosityForDamping(mesh, mat, xi)
    omega = modes.naturalFrequencies(mesh, mat, 1)[0]
    shape, nodeMass = modes.modeShape(mesh, mat, omega)
    w = qdem.World()
    p = w.addPiece(mesh, mat, reorder=False)
    p.vel[:] = 1e-3 * shape / np.abs(shape).max()  # small: linear regime
    return w, p, shape, nodeMass, omega


def _decay_rate(w, p, shape, mass, omega, dt, periods):
    amp = []
    for _ in range(int(periods * 2 * math.pi / omega / dt)):
        w.core.step(dt, 1)
        amp.append(float(np.sum(p.vel * shape * mass[:, None])))
    amp = np.abs(np.array(amp))
    half = int(math.pi / omega / dt)
    peaks = np.array([amp[i * half:(i + 1) * half].max() for i in range(2 * periods - 1)])
    t = (np.arange(len(peaks)) * math.pi / omega)
    # least-squares slope of ln(peak) against time, from the second peak on
    return -np.polyfit(t[1:], np.log(peaks[1:]), 1)[0]


def test_single_mode_damps_at_xi_omega_beyond_the_explicit_limit():
    xi = 0.3
    w, p, shape, mass, omega = _cube_mode(xi)
    w.core.viscousIntegration = IMPLICIT
    limits = w.stableDt()
    # omega dt = 0.03: the scheme's own damping error is about -xi omega dt = -0.9 %
    # (doc/formulation.md 2.1); the highest mode has xi ~ 5
    dt = 0.03 / omega
    assert dt > 2 * limits["combinedExplicit"]      # a step the explicit scheme cannot take
    assert dt < limits["combinedImplicit"] == limits["combined"]
    rate = _decay_rate(w, p, shape, mass, omega, dt, periods=3)
    assert rate == pytest.approx(xi * omega, rel=0.02)
    assert w.core.counts["viscousIterations"] > 0


def _wobble(implicit, dt, T=0.02, **kw):
    """A free cube spinning and ringing; node positions at T."""
    w = qdem.World()
    mat = rubber(viscosity=200.0)
    p = w.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), mat, vel=(0.1, 0, 0), angVel=(0, 2, 5))
    p.vel[:] += 0.2 * np.sin(17 * p.refPos)
    if implicit:
        w.core.viscousIntegration = IMPLICIT
        w.core.viscousTolerance = 1e-10
    for k, v in kw.items():
        setattr(w.core, k, v)
    n = int(round(T / dt))
    w.core.step(dt, n)
    return w, p


def test_implicit_and_explicit_agree_to_first_order():
    w, _ = _wobble(False, 1e-5, T=1e-5)
    dt0 = 0.4 * w.stableDt()["combinedExplicit"]  # (at 0.8 the explicit error is not yet asymptotic)
    T = 800 * dt0
    diffs = []
    for k in range(3):
        dt = dt0 / 2 ** k
        _, a = _wobble(False, dt, T)
        _, b = _wobble(True, dt, T)
        diffs.append(np.abs(a.pos - b.pos).max())
    # both first order in the viscous term, with errors of opposite sign: the
    # difference halves with dt
    assert 1.7 < diffs[0] / diffs[1] < 2.3
    assert 1.7 < diffs[1] / diffs[2] < 2.3


def _table1_cube():
    """Table 1's material on a 0.1 m cube of 0.025 m elements: viscosity sets
    the explicit step, far below the elastic one."""
    w = qdem.World()
    mat = qdem.QdemMat()  # Table 1
    p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), mat, angVel=(1, 2, 3))
    p.vel[:] += 0.5 * np.sin(31 * p.refPos)
    return w, p


def test_ten_times_the_explicit_viscous_limit_stays_bounded(scene):
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    w, p = _table1_cube()
    qdem.reset()
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), qdem.QdemMat(), angVel=(1, 2, 3))
    piece = qdem.defaultWorld().pieces[0]
    piece.vel[:] += 0.5 * np.sin(31 * piece.refPos)
    O.engines = [ForceResetter(), qdem.QdemEngine(viscousIntegration="implicit"), NewtonIntegrator(gravity=(0, 0, 0))]
    e = O.engines[1]
    s = e.stableDt()
    assert s["limitedBy"] == "elasticity (P-wave)"
    assert s["viscous"] < s["elastic"] / 20           # viscosity would set the explicit step
    assert s["combinedImplicit"] == s["combined"] > 10 * s["combinedExplicit"]
    O.dt = 10 * s["combinedExplicit"]
    ke0 = 0.5 * float(np.sum(piece.mass[:, None] * piece.vel ** 2))
    O.run(2000, True)
    ke = 0.5 * float(np.sum(piece.mass[:, None] * piece.vel ** 2))
    assert np.isfinite(piece.pos).all()
    assert ke < ke0                                       # viscosity took energy out, nothing blew up
    rigid = 0.5 * piece.totalMass * np.sum(piece.velocity ** 2)
    assert ke > rigid                                     # (and the spin is still there)
    # The same step with explicit viscosity is refused, naming the limit and the option ...
    e.viscousIntegration = "explicit"
    with pytest.raises(qdem.StabilityError, match="limited by viscosity.*viscousIntegration='implicit'"):
        e.stepOnce()
    # ... rightly: forced through without the check it explodes, and the
    # step whose update is no longer finite stops (before: a NaN state).
    with pytest.raises(qdem.StabilityError, match="has a (velocity|position) that is not finite"):
        w.core.step(10 * s["combinedExplicit"], 300)


def _momentum(p):
    return np.sum(p.mass[:, None] * p.vel, axis=0)


def test_momentum_is_conserved_whatever_the_tolerance(rng):
    w, p = _table1_cube()
    p.vel[:] += rng.normal(0, 0.3, p.vel.shape)  # no symmetry to hide behind
    w.core.gravity = (0, 0, -9.81)
    w.core.viscousIntegration = IMPLICIT
    w.core.viscousTolerance = 0.4  # a few iterations only: far from converged
    p0 = _momentum(p)
    scale = float(np.sum(p.mass) * np.abs(p.vel).max())
    dt = 0.8 * w.stableDt()["combined"]
    for k in range(1, 21):
        w.core.step(dt, 10)
        expected = p0 + np.sum(p.mass) * np.array([0, 0, -9.81]) * 10 * k * dt  # gravity's impulse only
        assert np.abs(_momentum(p) - expected).max() < 1e-13 * scale
    assert w.core.counts["viscousIterations"] >= 1


def test_blocked_dofs_keep_their_velocity_and_the_rest_follows_explicit():
    """A bar held at one end (blocked, at rest) and pushed at the other (blocked,
    prescribed velocity): the blocked nodes keep their velocities; the free
    ones move as with explicit viscosity at a step both can take."""
    def run(implicit):
        w = qdem.World()
        p = w.addPiece(qdem.boxMesh((0.4, 0.1, 0.1), (8, 2, 2)), rubber(viscosity=300.0), reorder=False)
        x = p.refPos[:, 0]
        held, pushed = x < x.min() + 1e-9, x > x.max() - 1e-9
        p.blocked[held] = 7
        p.blocked[pushed] = 1  # x only
        p.vel[pushed, 0] = 0.3
        w.core.gravity = (0, 0, -9.81)
        if implicit:
            w.core.viscousIntegration = IMPLICIT
            w.core.viscousTolerance = 1e-10
        dt = 0.2 * w.stableDt()["combinedExplicit"]
        w.core.step(dt, 3000)
        return p, held, pushed
    a, held, pushed = run(True)
    b, _, _ = run(False)
    assert np.array_equal(a.pos[held], a.refPos[held])
    assert np.all(a.vel[pushed, 0] == 0.3)
    moved = np.abs(b.pos - b.refPos).max()
    assert moved > 1e-3
    # first-order apart at this step: ~3e-5 of the motion (treating the blocked rows as
    # unknowns of the solve instead gives 4e-3)
    assert np.abs(a.pos - b.pos).max() < 2e-4 * moved


def test_a_sleeping_piece_changes_nothing():
    def run(withSleeper, dt=2e-4):  # (a second piece adds a contact limit: dt fixed)
        w = qdem.World()
        p = w.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), rubber(viscosity=500.0), reorder=False,
                       angVel=(0, 3, 1))
        p.vel[:] += 0.1 * np.sin(11 * p.refPos)
        if withSleeper:
            q = w.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), rubber(viscosity=500.0), pos=(5, 0, 0),
                           reorder=False, vel=(1, 0, 0))
            q.dynamic = False  # put to sleep where it is
        w.core.viscousIntegration = IMPLICIT
        assert dt < w.stableDt()["combined"]
        w.core.step(dt, 500)
        return w, p
    _, a = run(False)
    w, b = run(True)
    assert np.abs(a.pos - b.pos).max() < 1e-12
    q = w.pieces[1]
    assert np.array_equal(q.pos, q.refPos) and not np.any(q.vel)  # (refPos: where it was placed)


def test_energy_ledger_balances_with_implicit_viscosity(scene):
    """A block dropped on a floor at 5x the explicit viscous limit: O.energy sums to
    zero within 1 % of the gravity work, and viscosity dissipated."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mat = rubber(viscosity=3000.0)
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.3), ori=((1, 1, 0), 0.3))
    O.bodies.append(utils.wall(0, axis=2))
    O.engines = [ForceResetter(), qdem.QdemEngine(viscousIntegration="implicit"),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.trackEnergy = True
    s = O.engines[1].stableDt()
    O.dt = min(5 * s["combinedExplicit"], 0.8 * s["combined"])
    assert O.dt > 4 * s["combinedExplicit"]
    worst = 0.0
    for _ in range(30):
        O.run(int(0.01 / O.dt), True)
        total = sum(O.energy[k] for k in qdem.yade.engine.ENERGY_KEYS.values())
        worst = max(worst, abs(total))
    assert O.energy["qdemGravWork"] < 0
    assert O.energy["qdemViscDissip"] > 0.05 * abs(O.energy["qdemGravWork"])
    assert worst < 0.01 * abs(O.energy["qdemGravWork"])


def test_free_decay_ledger_does_not_drift():
    """One mode released from rest, displaced, decaying freely: kinetic + elastic +
    dissipated stays at the start's to the leapfrog's O(dt^3) for one mode
    (doc/formulation.md 2.1), though the viscous term takes 99 % of it."""
    w, p, shape, mass, omega = _cube_mode(0.3, cells=3)
    p.pos[:] = p.refPos + 1e-4 * shape / np.abs(shape).max()
    p.vel[:] = 0
    w.core.viscousIntegration = IMPLICIT
    w.core.viscousTolerance = 1e-12
    w.core.trackEnergy = True
    dt = 0.05 / omega
    w.core.step(dt, 1)
    e0 = w.core.energy
    start = e0["kinetic"] + e0["elastic"] + e0["viscous"]
    w.core.step(dt, int(4 * 2 * math.pi / omega / dt))
    e = w.core.energy
    assert e["viscous"] > 0.99 * start
    assert abs(e["kinetic"] + e["elastic"] + e["viscous"] - start) < 1e-3 * start


def test_same_thread_count_gives_the_same_bits_and_two_threads_agree_with_one():
    try:
        res = {}
        for th in (1, 2, 2):
            qdem._core.setThreads(th)
            _, p = _wobble(True, 2e-6, T=2e-3, viscousTolerance=1e-6)
            res.setdefault(th, []).append(p.pos.copy())
    finally:
        qdem._core.setThreads(2)
    assert np.array_equal(res[2][0], res[2][1])
    assert np.abs(res[1][0] - res[2][0]).max() < 1e-9 * np.abs(res[1][0]).max()


def test_bad_settings_are_refused_with_the_allowed_values():
    with pytest.raises(ValueError, match="viscousIntegration.*'explicit', 'implicit'"):
        qdem.QdemEngine(viscousIntegration="semi")
    for bad in (0, 1.0, -1e-6, float("nan")):
        with pytest.raises(ValueError, match="viscousTolerance.*must lie in"):
            qdem.QdemEngine(viscousTolerance=bad)
    w = qdem.World()
    with pytest.raises(Exception, match="viscousIntegration.*must be one of"):
        w.core.viscousIntegration = 2


def test_yade_sphere_on_an_implicitly_viscous_slab_balances_momentum_through_the_floor(scene):
    """A YADE sphere bouncing on a viscous slab (implicit, beyond the explicit
    viscous limit): its contact forces are explicit forces of the solve, and
    sphere + slab momentum changes by the floor's impulse and gravity's only."""
    from yade import FrictMat, Vector3
    from test_spheres import _engines, _slab
    O = scene
    g = np.array([0, 0, -9.81])
    mat, slab, floor = _slab(O, young=1e8, viscosity=3e4)
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
    from yade import utils
    sid = O.bodies.append(utils.sphere((0.013, 0.007, 0.055), 0.005, material=fm))
    O.bodies[sid].state.vel = Vector3(0.3, 0, -1.0)
    O.engines = _engines(viscousIntegration="implicit")
    s = O.engines[3].stableDt()
    O.dt = 0.5 * s["combined"]
    assert O.dt > 2 * s["combinedExplicit"]
    b = O.bodies[sid]
    m = b.state.mass

    def momentum():
        return m * np.array(b.state.vel) + slab.momentum

    p0 = momentum()
    impulse = np.zeros(3)
    touched = 0
    for _ in range(1500):
        O.step()
        impulse -= np.array(O.forces.f(floor)) * O.dt
        touched += O.engines[3].world.core.contactCounts["sphere"] > 0
    gravityImpulse = (m + slab.totalMass) * g * O.time
    scale = m * 1.0 + slab.totalMass * 9.81 * O.time
    assert touched > 10
    assert b.state.vel[2] > 0  # it bounced
    assert np.abs(momentum() - p0 - impulse - gravityImpulse).max() < 1e-9 * scale


def _warm_cube(tol=1e-6):
    w, p = _table1_cube()
    w.core.gravity = (0, 0, -9.81)
    w.core.viscousIntegration = IMPLICIT
    w.core.viscousTolerance = tol
    # The warm start's gain is read off Jacobi's iteration counts: the
    # co-rotated Cholesky preconditioner takes 1-2 from either start
    # (test_viscous_preconditioner.py).
    w.core.viscousPreconditioner = 0
    return w, p, 0.8 * w.stableDt()["combined"]


def _iterations(w, dt, steps):
    its = []
    for _ in range(steps):
        w.core.step(dt, 1)
        its.append(w.core.counts["viscousIterations"])
    return np.array(its)


def test_the_solve_starts_from_the_last_steps_change():
    w, p, dt = _warm_cube()
    warm = _iterations(w, dt, 40)[20:]              # (past the first steps' fast transient)
    assert w.core.counts["viscousWarmStart"] == 1
    # A pause of the solve (one explicit step in between) leaves no last change: from 0.
    w.core.viscousIntegration = 0
    w.core.step(dt / 40, 1)
    w.core.viscousIntegration = IMPLICIT
    cold = _iterations(w, dt, 1)[0]
    assert w.core.counts["viscousWarmStart"] == 0
    assert cold >= 20 and warm.mean() < 0.6 * cold, (cold, warm)


def test_a_restart_continues_the_warm_started_solve_on_the_same_bits(tmp_path):
    path = str(tmp_path / "run.qdem.npz")
    w, p, dt = _warm_cube(tol=1e-4)
    w.core.step(dt, 30)
    qdem.saveState(path, world=w)
    its = _iterations(w, dt, 30)
    w2, p2, _ = _warm_cube(tol=1e-4)
    qdem.loadState(path, world=w2)
    its2 = _iterations(w2, dt, 30)
    assert np.array_equal(its2, its)
    assert np.array_equal(p2.pos, p.pos) and np.array_equal(p2.vel, p.vel)
    # A state saved before the warm start existed (no such fields) loads; its
    # first solve starts from 0 and the run stays within the solve's tolerance.
    data = {k: v for k, v in np.load(path).items() if "viscousWarm" not in k}
    assert len(data) == len(np.load(path).files) - 2
    old = str(tmp_path / "old.npz")
    np.savez(old, **data)
    w3, p3, _ = _warm_cube(tol=1e-4)
    qdem.loadState(old, world=w3)
    its3 = _iterations(w3, dt, 30)
    assert its3[0] > its[0] and its3[0] > 2 * its3[1:].mean()
    assert np.abs(p3.vel - p.vel).max() < 1e-3 * np.abs(p.vel).max()
