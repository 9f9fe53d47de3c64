"""Selective mass scaling (addPiece(targetDt=..., maxAddedMass=...), doc/meshes.md):
mass is added to the slivers only, just enough that the piece's element step
(elastic and viscous, as stableDt computes it) reaches targetDt; the figures
reported equal a direct computation; the added mass is real mass (momentum,
weight, rest height); too much is refused; restarts, O.save/O.load and MPI
keep it."""
import os
import subprocess
import textwrap
import warnings

import numpy as np
import pytest

import qdem
from conftest import lame, rubber

HERE = os.path.dirname(os.path.abspath(__file__))


def sliverMesh(size=0.1, cells=6, squash=0.97, surface=False):
    """boxMesh with one node moved `squash` of the way to the face opposite it
    in one of its tets: that tet and the ones sharing its face's plane become
    slivers (height/longest edge about (1 - squash) x 0.4; with squash 0.97
    the viscous element step drops 64x).  An interior node
    (the one nearest the centre), or with surface=True a node of the top face."""
    m = qdem.boxMesh((size, size, size), (cells, cells, cells))
    x, t = np.array(m.nodes, dtype=float), np.array(m.tets)
    if surface:
        top = np.where(np.isclose(x[:, 2], x[:, 2].max()) & (np.abs(x[:, :2]).max(axis=1) < 0.3 * size))[0]
        node = top[0]
    else:
        node = int(np.argmin(np.linalg.norm(x, axis=1)))
    for tet in np.where((t == node).any(axis=1))[0]:
        a, b, c = x[[v for v in t[tet] if v != node]]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        h = np.dot(x[node] - a, n)
        y = x.copy()
        y[node] -= squash * h * n
        if (_volumes(y, t) > 0).all() and (not surface or n[2] > 0.5):
            return y, t
    raise AssertionError("no tet to flatten")


def _volumes(x, t):
    a, b, c, d = (x[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def _quality(x, t):
    """Smallest height over longest edge of each tet."""
    V = _volumes(x, t)
    p = [x[t[:, k]] for k in range(4)]
    h = np.full(len(t), np.inf)
    for k in range(4):
        a, b, c = (p[j] for j in range(4) if j != k)
        h = np.minimum(h, 6 * V / np.linalg.norm(np.cross(b - a, c - a), axis=1))
    longest = np.max([np.linalg.norm(p[i] - p[j], axis=1) for i in range(4) for j in range(i + 1, 4)], axis=0)
    return h / longest


def hookeK(xe, lam, mu):
    """The 12x12 small-strain stiffness of one tet, straight from its shape gradients."""
    Dm = np.column_stack([xe[1] - xe[0], xe[2] - xe[0], xe[3] - xe[0]])
    V = np.linalg.det(Dm) / 6.0
    B = np.linalg.inv(Dm)
    G = np.vstack([-B.sum(axis=0), B])
    K = np.zeros((12, 12))
    for a in range(4):
        for b in range(4):
            K[3 * a:3 * a + 3, 3 * b:3 * b + 3] = V * (lam * np.outer(G[a], G[b]) + mu * np.outer(G[b], G[a])
                                                       + mu * G[a] @ G[b] * np.eye(3))
    return K, V


def directAddedMass(x, t, mat, dt):
    """Per tet: max(0, k_e dt (dt + 2 beta) - rho V), k_e the stiffness's largest eigenvalue."""
    lam, mu = lame(mat)
    beta = mat.viscosity / mu
    out = np.zeros(len(t))
    for e, tet in enumerate(t):
        K, V = hookeK(x[tet], lam, mu)
        out[e] = max(0.0, np.linalg.eigvalsh(K).max() * dt * (dt + 2 * beta) - mat.density * V)
    return out


MAT = dict(young=1e6, poisson=0.3, density=1100.0, viscosity=5.0, radius=0.004)


def test_slivers_get_just_the_mass_that_brings_the_step_to_target():
    x, t = sliverMesh()
    mat = rubber(**MAT)
    plain = qdem.World()
    p0 = plain.addPiece((x, t), mat, reorder=False)
    s0 = plain.stableDt()
    regular = qdem.World()
    regular.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), rubber(**MAT))
    sReg = regular.stableDt()
    target = 0.5 * sReg["viscous"]
    assert s0["viscous"] < target / 20, "the slivers must cut the step (%g vs %g)" % (s0["viscous"], target)
    assert p0.addedMass == 0 and p0.addedMassFraction == 0 and p0.addedMassMaxNodeShare == 0

    w = qdem.World()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # interior slivers, no contacts: nothing to warn about
        p = w.addPiece((x, t), rubber(**MAT), reorder=False, targetDt=target, maxAddedMass=0.05)
    s = w.stableDt()
    # The claim, exactly: the piece's element steps reach the target, and only just.
    assert s["elastic"] >= target and s["viscous"] >= target
    assert s["viscous"] <= target * (1 + 1e-9)
    # The added mass per tet is what the energy condition asks, computed here from scratch.
    direct = directAddedMass(x, t, mat, target)
    got = np.array(p.addedMassPerTet)
    assert np.count_nonzero(got) == np.count_nonzero(direct) >= 1
    # The slivers only: the tets whose height / longest edge is below 0.05 (0.41 elsewhere).
    assert set(np.nonzero(got)[0]) == set(np.nonzero(_quality(x, t) < 0.05)[0])
    np.testing.assert_allclose(got, direct, rtol=1e-9, atol=1e-15 * direct.max())
    # Lumped: a quarter of each element's added mass on each of its nodes, on top of rho V / 4.
    own = np.zeros(len(x))
    add = np.zeros(len(x))
    V = _volumes(x, t)
    for k in range(4):
        np.add.at(own, t[:, k], mat.density * V / 4)
        np.add.at(add, t[:, k], got / 4)
    np.testing.assert_allclose(p.mass, own + add, rtol=1e-12)
    physical = mat.density * V.sum()
    assert p.addedMass == pytest.approx(got.sum(), rel=1e-12)
    assert p.totalMass == pytest.approx(physical + got.sum(), rel=1e-12)
    assert p.addedMassFraction == pytest.approx(got.sum() / physical, rel=1e-12)
    share = add / own
    assert p.addedMassMaxNodeShare == pytest.approx(share.max(), rel=1e-12)
    assert p.addedMassMaxNode == int(np.argmax(share))
    assert p.targetDt == target
    print("step %.3g -> %.3g s (target %.3g), added %.3g %% of the mass, largest node share %.3g"
          % (s0["viscous"], s["viscous"], target, 100 * p.addedMassFraction, p.addedMassMaxNodeShare))


def test_too_much_added_mass_is_refused_naming_figures_and_remedies():
    x, t = sliverMesh()
    w = qdem.World()
    mat = rubber(**MAT)
    with pytest.raises(ValueError) as e:
        w.addPiece((x, t), mat, targetDt=1e-3, maxAddedMass=0.01)
    msg = str(e.value)
    for needle in ("targetDt=0.001", "maxAddedMass=1 %", "qdem.improveMesh(mesh)", "larger maxAddedMass",
                   "smaller targetDt", "elements are below targetDt"):
        assert needle in msg, msg
    assert w.core.nPieces == 0 and w.core.nNodes == 0  # the world as it was
    assert not getattr(mat, "_inUse", False)
    with pytest.raises(ValueError, match="targetDt"):
        w.addPiece((x, t), mat, targetDt=-1.0)
    with pytest.raises(ValueError, match="maxAddedMass"):
        w.addPiece((x, t), mat, targetDt=1e-4, maxAddedMass=-0.1)


def test_mass_on_surface_nodes_and_an_unreachable_contact_limit_are_warned():
    x, t = sliverMesh(surface=True)
    w = qdem.World()
    mat = rubber(**MAT)
    probe = qdem.World()
    probe.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), rubber(**MAT))
    target = 0.5 * probe.stableDt()["viscous"]
    with pytest.warns(RuntimeWarning, match="surface nodes"):
        p = w.addPiece((x, t), mat, targetDt=target, maxAddedMass=0.05)
    assert p.addedMass > 0
    w2 = qdem.World()
    stiff = rubber(**dict(MAT, radius=0.05, young=1e6))
    probe2 = qdem.World()
    probe2.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), stiff)
    c2 = probe2.core.rigidContactLimit(0)[0]
    with pytest.warns(RuntimeWarning, match="contact springs allow against a rigid wall"):
        w2.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), stiff, targetDt=2 * c2, maxAddedMass=10)


def _free(scaled, steps=400, viscosity=5.0):
    x, t = sliverMesh()
    w = qdem.World()
    mat = rubber(**dict(MAT, viscosity=viscosity))
    probe = qdem.World()
    probe.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), rubber(**dict(MAT, viscosity=viscosity)))
    target = 0.5 * probe.stableDt()["viscous"]
    p = w.addPiece((x, t), mat, vel=(0.3, -0.1, 0.2), angVel=(2.0, 1.0, -3.0),
                   **({"targetDt": target, "maxAddedMass": 0.05} if scaled else {}))
    return w, p, target


def test_momentum_and_energy_are_conserved_with_the_added_mass():
    w, p, target = _free(True, viscosity=0.0)
    rng = np.random.default_rng(3)
    p.vel[:] += rng.normal(0, 0.05, p.vel.shape)  # internal vibration
    w.core.trackEnergy = True
    m = np.array(p.mass)
    P0 = (m[:, None] * np.array(p.vel)).sum(axis=0)
    L0 = p.angularMomentumAbout((0, 0, 0))
    dt = 0.9 * w.stableDt()["combined"]
    assert dt > 0.9 * 0.99 * target
    w.core.step(dt, 1500)
    P1 = (m[:, None] * np.array(p.vel)).sum(axis=0)
    scale = np.abs(m[:, None] * np.array(p.vel)).sum()
    assert np.abs(P1 - P0).max() <= 1e-12 * scale
    L1 = p.angularMomentumAbout((0, 0, 0))
    # Leapfrog keeps angular momentum to O(dt^2) of the spin; the added mass is in it.
    assert np.abs(L1 - L0).max() <= 1e-3 * np.abs(L0).max()
    e = w.core.energy
    assert abs(e["total"] - (e["kinetic"] + e["elastic"])) < 1e-9  # no dissipation booked elsewhere
    # Kinetic energy counts the added mass: 1/2 sum m v^2 over the scaled masses.
    ek = 0.5 * (m * (np.array(p.vel) ** 2).sum(axis=1)).sum()
    assert e["kinetic"] == pytest.approx(ek, rel=0.05)  # (the ledger's is at the half step)


def test_a_scaled_sliver_block_drops_and_rests_where_a_regular_block_does():
    g = 9.81
    mat = dict(MAT, viscosity=20.0, restitution=0.3, frictionWall=0.5)

    def drop(mesh, **kw):
        w = qdem.World()
        p = w.addPiece(mesh, rubber(**mat), pos=(0, 0, 0.06), **kw)
        o = qdem._core.Obstacle()
        o.kind, o.bodyId, o.axis, o.sense, o.young = 0, 0, 2, 1, 0.0
        w.core.setObstacles([o])
        w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
        w.core.gravity = (0, 0, -g)
        dt = 0.8 * w.stableDt()["combined"]
        n = int(1.0 / dt)
        w.core.step(dt, n)
        return p, n, dt

    ref, nRef, _ = drop(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)))
    probe = qdem.World()
    probe.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), rubber(**mat))
    target = 0.5 * probe.stableDt()["viscous"]
    x, t = sliverMesh()
    p, n, dt = drop((x, t), targetDt=target, maxAddedMass=0.05)
    assert 0 < p.addedMassFraction < 0.05
    # At rest on the floor, its centre where the regular block's is: the
    # weight (added mass included) on the same contacts.
    assert np.abs(p.velocity).max() < 1e-3 and np.abs(ref.velocity).max() < 1e-3
    zc, zr = p.centroid[2], ref.centroid[2]
    print("rest height %.7f (regular block %.7f)" % (zc, zr))
    assert abs(zc - zr) < 2e-4 * 0.1, (zc, zr)
    bottom = np.array(p.pos)[:, 2].min()
    assert 0 < bottom < MAT["radius"]
    # The weight it puts on the floor is the whole mass's, added mass included.
    assert n <= 3 * nRef


def test_restart_and_reload_keep_the_added_mass(tmp_path):
    path = str(tmp_path / "run.qdem.npz")

    def scene(scaled=True):
        w = qdem.World()
        x, t = sliverMesh()
        probe = qdem.World()
        probe.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (6, 6, 6)), rubber(**MAT))
        target = 0.5 * probe.stableDt()["viscous"]
        w.addPiece((x, t), rubber(**MAT), pos=(0, 0, 0.2), vel=(0.1, 0, -0.5), angVel=(0, 3, 0),
                   **({"targetDt": target, "maxAddedMass": 0.05} if scaled else {}))
        w.core.gravity = (0, 0, -9.81)
        return w, target

    w, target = scene()
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 300)
    qdem.saveState(path, world=w)
    w.core.step(dt, 300)
    w2, _ = scene()
    qdem.loadState(path, world=w2)
    w2.core.step(dt, 300)
    assert np.array_equal(w2.core.pos, w.core.pos) and np.array_equal(w2.core.vel, w.core.vel)
    # A scene built without the mass scaling is refused, naming it.
    w3, _ = scene(scaled=False)
    with pytest.raises(ValueError, match="added by mass scaling"):
        qdem.loadState(path, world=w3)


def _yade(tmp_path, code):
    path = tmp_path / "s.py"
    path.write_text(textwrap.dedent(code))
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONPATH=os.pathsep.join([HERE, os.environ.get("PYTHONPATH", "")]))
    return subprocess.run(["timeout", "300", "yade", "-n", "-x", str(path)], cwd=str(tmp_path), env=env,
                          capture_output=True, text=True)


def test_yade_save_load_and_reset_keep_or_drop_the_added_mass(tmp_path):
    r = _yade(tmp_path, """
import numpy as np, qdem
from yade import O, ForceResetter, NewtonIntegrator, utils
from test_mass_scaling import sliverMesh, MAT
from conftest import rubber
x, t = sliverMesh()
p = qdem.addPiece((x, t), rubber(**MAT), pos=(0, 0, 0.1), targetDt=2e-5, maxAddedMass=0.05)
assert p.addedMass > 0
O.bodies.append(utils.wall(0, axis=2, sense=1))
O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
O.dt = 0.8 * qe.stableTimeStep()
O.run(200, True)
O.save("scene.yade.gz")
mass, added = np.array(p.mass), p.addedMass
O.run(300, True)
ref = np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel])
O.load("scene.yade.gz")
q = qdem.defaultWorld().pieces[0]
assert np.array_equal(np.array(q.mass), mass) and q.addedMass == added and q.targetDt == 2e-5
O.run(300, True)
now = np.concatenate([qdem.defaultWorld().core.pos, qdem.defaultWorld().core.vel])
assert np.array_equal(now, ref), np.abs(now - ref).max()
O.reset()
p2 = qdem.addPiece((x, t), rubber(**MAT))
assert p2.addedMass == 0 and qdem.defaultWorld().core.tetAddedMass.sum() == 0
print("ALLOK")
""")
    assert r.returncode == 0 and "ALLOK" in r.stdout, r.stdout[-3000:] + r.stderr[-3000:]


def test_two_ranks_equal_serial_with_mass_scaling():
    from mpi_launch import mpirun, python, requireMpi, result
    requireMpi()
    rc, out = mpirun(2, python("tests/mpi/check_mass_scaling.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["addedMass"] > 0
    assert r["massEqual"]
    assert r["maxDisplacement"] > 0.01
    assert r["dx"] <= 1e-12 * r["maxDisplacement"]
    assert r["dv"] <= 1e-9 * r["vmax"]
