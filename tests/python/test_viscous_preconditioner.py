"""viscousPreconditioner='cholesky': the implicit viscous solve preconditioned
per piece by the Cholesky factor of M + dt C of its reference shape, rotated
with the piece's best-fit rotation (doc/formulation.md 2.1, "Preconditioner").
The same answer as Jacobi within the solve's tolerance, exact momentum, a few
iterations where Jacobi takes tens (also with the piece turned far from its
reference orientation), a new factor when dt changes (the material and the
masses are fixed once a piece is added; they are part of the factor's key
all the same), restarts on the same bits."""
import numpy as np
import pytest

import qdem

IMPLICIT, JACOBI, CHOLESKY = 1, 0, 1


def _rotation(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _cubes(pre, tol=1e-3, turn=None, cells=5):
    """Two free cubes of Table 1's material (viscosity sets the explicit step,
    far below the elastic one: the real-size regime), spinning and ringing;
    the second turned by `turn` (a rotation matrix) from its reference shape."""
    w = qdem.World()
    mat = qdem.QdemMat()  # Table 1
    ps = []
    for k in range(2):
        p = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (cells,) * 3), mat, pos=(0.3 * k, 0, 0), angVel=(10, 20, 30))
        if k == 1 and turn is not None:
            c = p.pos.mean(axis=0)
            p.pos[:] = (p.pos - c) @ turn.T + c
            p.vel[:] = p.vel @ turn.T
        p.vel[:] += 0.5 * np.sin(31 * p.refPos)
        ps.append(p)
    w.core.gravity = (0, 0, -9.81)
    w.core.viscousIntegration = IMPLICIT
    w.core.viscousTolerance = tol
    w.core.viscousPreconditioner = pre
    return w, ps, 0.8 * w.stableDt()["combined"]


def _run(w, dt, steps):
    its = []
    for _ in range(steps):
        w.core.step(dt, 1)
        its.append(w.core.counts["viscousIterations"])
    return np.array(its)


def _momentum(ps):
    return sum((p.mass[:, None] * p.vel).sum(axis=0) for p in ps)


def test_cholesky_is_the_default():
    assert qdem.World().core.viscousPreconditioner == CHOLESKY


def test_same_motion_as_jacobi_within_the_tolerance_and_exact_momentum():
    tol = 1e-6
    res = {}
    for pre in (JACOBI, CHOLESKY):
        w, ps, dt = _cubes(pre, tol=tol)
        p0 = _momentum(ps)
        its = _run(w, dt, 200)
        mass = sum(float(p.mass.sum()) for p in ps)
        expected = p0 + mass * np.array([0, 0, -9.81]) * 200 * dt  # gravity's impulse only
        scale = mass * max(float(np.abs(p.vel).max()) for p in ps)
        assert np.abs(_momentum(ps) - expected).max() < 1e-13 * scale, pre
        res[pre] = (np.vstack([p.vel for p in ps]), np.vstack([p.pos for p in ps]), its)
    (vj, xj, itj), (vc, xc, itc) = res[JACOBI], res[CHOLESKY]
    vmax = np.abs(vj).max()
    # Each step's velocity change within tol of the exact one (in the
    # kinetic-energy norm): the two runs differ by about tol times the
    # velocities, not by rounding only, and by far less than the motion.
    dv = np.abs(vc - vj).max()
    assert 0 < dv < 100 * tol * vmax, (dv, vmax)
    assert np.abs(xc - xj).max() < 1e-9
    assert itc.mean() < 0.2 * itj.mean(), (itc.mean(), itj.mean())


@pytest.mark.parametrize("turned", [False, True])
def test_a_few_iterations_where_jacobi_takes_tens(turned):
    """Cold (no warm start): every solve from zero.  At Table 1's viscosity
    Jacobi needs tens of iterations; the co-rotated factor, exact for a rigidly
    rotated reference shape, a few, the piece turned 80 degrees as well."""
    turn = _rotation((1, -2, 0.5), np.radians(80)) if turned else None
    its = {}
    for pre in (JACOBI, CHOLESKY):
        w, ps, dt = _cubes(pre, turn=turn)
        w.core.viscousWarmStart = False
        its[pre] = _run(w, dt, 30)
    assert its[JACOBI].min() >= 20, its[JACOBI]
    assert its[CHOLESKY].max() <= 4, its[CHOLESKY]


def test_a_turned_piece_needs_no_more_iterations_than_one_at_rest():
    """The factor is rotated with the piece: a cube turned 90 degrees from its
    reference shape is solved as fast as one in it."""
    w0, _, dt = _cubes(CHOLESKY)
    w1, _, _ = _cubes(CHOLESKY, turn=_rotation((0, 0, 1), np.pi / 2))
    for w in (w0, w1):
        w.core.viscousWarmStart = False
    assert np.abs(_run(w0, dt, 10) - _run(w1, dt, 10)).max() <= 1


def test_a_new_factor_when_dt_changes():
    w, ps, dt = _cubes(CHOLESKY)
    _run(w, dt, 3)
    n = w.core.counts["viscousFactorizations"]
    assert n == 2  # once per piece
    _run(w, 1.005 * dt, 3)  # within 1 %: the factor serves
    assert w.core.counts["viscousFactorizations"] == n
    _run(w, 0.5 * dt, 3)
    assert w.core.counts["viscousFactorizations"] == n + 2
    its = _run(w, 0.5 * dt, 5)
    assert its.max() <= 4
    # A switch to Jacobi and back: the factors kept.
    w.core.viscousPreconditioner = JACOBI
    _run(w, 0.5 * dt, 1)
    w.core.viscousPreconditioner = CHOLESKY
    _run(w, 0.5 * dt, 1)
    assert w.core.counts["viscousFactorizations"] == n + 2


def test_blocked_dofs_keep_their_velocity():
    """Blocked DOFs are left out of the iteration (the preconditioner is
    zeroed on them: Pi A^-1 Pi, still symmetric positive definite on the
    free DOFs); a weaker fit than on a free piece, still ahead of Jacobi."""
    its = {}
    for pre in (JACOBI, CHOLESKY):
        w, ps, dt = _cubes(pre)
        w.core.viscousWarmStart = False
        p = ps[0]
        held = np.where(p.refPos[:, 2] < p.refPos[:, 2].min() + 1e-9)[0]
        p.vel[held] = 0
        p.blocked[held] = 7
        pushed = np.where(p.refPos[:, 0] > p.refPos[:, 0].max() - 1e-9)[0]
        p.blocked[pushed] = p.blocked[pushed] | 1  # x (all three on the edge it shares with the held face)
        vx = p.vel[pushed, 0].copy()
        its[pre] = _run(w, dt, 20)
        assert np.array_equal(p.vel[held], 0 * p.vel[held])
        assert np.array_equal(p.vel[pushed, 0], vx)
    assert its[CHOLESKY].max() < 0.5 * its[JACOBI].min(), its


def test_a_restart_continues_on_the_same_bits(tmp_path):
    path = str(tmp_path / "run.qdem.npz")
    w, ps, dt = _cubes(CHOLESKY, tol=1e-4)
    _run(w, dt, 20)
    qdem.saveState(path, world=w)
    its = _run(w, dt, 20)
    w2, ps2, _ = _cubes(CHOLESKY, tol=1e-4)
    qdem.loadState(path, world=w2)
    its2 = _run(w2, dt, 20)
    assert np.array_equal(its2, its)
    for p, p2 in zip(ps, ps2):
        assert np.array_equal(p2.pos, p.pos) and np.array_equal(p2.vel, p.vel)
    assert w2.core.counts["viscousFactorizations"] == 2


def test_bad_preconditioner_is_refused_with_the_choices():
    w = qdem.World()
    with pytest.raises(ValueError, match=r"viscousPreconditioner=2 is invalid.*'jacobi'.*'cholesky'"):
        w.core.viscousPreconditioner = 2
