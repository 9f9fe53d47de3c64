"""YADE spheres and clumps against QDEM pieces (issue 5): restitution, momentum
through the floor, rolling by friction torque, a clump at rest, a packing."""
import math
import re

import numpy as np
import pytest

import qdem
from conftest import rubber


def _engines(gravity=(0, 0, -9.81), damping=0.0, **kw):
    from yade import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, Ig2_Sphere_Sphere_ScGeom,
                      Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                      Ip2_FrictMat_FrictMat_FrictPhys, Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                            [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
            qdem.QdemEngine(**kw), NewtonIntegrator(gravity=gravity, damping=damping)]


def _lawRebound(kn, mS, mT, e):
    """Rebound/impact speed ratio of the law for a sphere of mass mS on a
    (much heavier, stiff) surface whose contact node has mass mT: spring kn,
    dashpot from the reduced mass, no tension.  Integrated finely in 1D."""
    le = math.log(e)
    xi = -le / math.sqrt(math.pi**2 + le**2)
    c = 2 * xi * math.sqrt(kn * mS * mT / (mS + mT))
    x, v, h = 0.0, -1.0, math.pi * math.sqrt(mS / kn) / 20000
    while not (x > 0 and v > 0):
        f = max(0.0, -kn * x - c * v) if x < 0 else 0.0
        v += h * f / mS
        x += h * v
    return v


def _slab(O, young=1e9, size=(0.2, 0.2, 0.04), cells=(10, 10, 2), **kw):
    from yade import utils
    mat = qdem.QdemMat(**dict(dict(young=young, poisson=0.3, density=2000.0, viscosity=0.0, radius=0.002,
                                   restitution=0.5), **kw))
    slab = qdem.addPiece(qdem.boxMesh(size, cells), mat, pos=(0, 0, size[2] / 2 + mat.radius))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    return mat, slab, floor


def _runThroughOneImpact(O, limit=4000):
    """Steps until the sphere has touched the piece and let go again."""
    touched = False
    for _ in range(limit):
        O.step()
        n = O.engines[3].world.core.contactCounts["sphere"]
        touched = touched or n > 0
        if touched and n == 0:
            break
    assert touched and n == 0, "the sphere must touch the piece and come off it"


def test_sphere_rebounds_from_a_slab_with_the_law_restitution(scene):
    from yade import FrictMat, Vector3, utils
    O = scene
    mat, slab, _ = _slab(O)
    fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=100))
    R = 0.005
    # Straight above a top-face node: the contact node is that node.
    top = np.isclose(slab.refPos[:, 2], slab.refPos[:, 2].max())
    node = np.flatnonzero(top & np.isclose(slab.refPos[:, 0], 0.02) & np.isclose(slab.refPos[:, 1], 0.04))[0]
    x = slab.pos[node]
    sid = O.bodies.append(utils.sphere((x[0], x[1], x[2] + mat.radius + R + 1e-4), R, material=fm))
    O.bodies[sid].state.vel = Vector3(0, 0, -1.0)
    O.engines = _engines(gravity=(0, 0, 0))
    O.dt = 0.25 * O.engines[3].stableDt()["combined"]
    _runThroughOneImpact(O)
    b = O.bodies[sid]
    kn = 2 * (1e6 * R) * (mat.young * mat.radius) / (1e6 * R + mat.young * mat.radius)
    predicted = _lawRebound(kn, b.state.mass, slab.mass[node], 0.5)
    assert b.state.vel[2] == pytest.approx(predicted, rel=0.05)
    assert abs(b.state.vel[0]) + abs(b.state.vel[1]) < 1e-3  # head-on: no sideways kick


def test_sphere_and_slab_momentum_balances_against_the_floor(scene):
    from yade import FrictMat, Vector3, utils
    O = scene
    g = np.array([0, 0, -9.81])
    mat, slab, floor = _slab(O, young=1e8, viscosity=50.0)
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
    sid = O.bodies.append(utils.sphere((0.013, 0.007, 0.055), 0.005, material=fm))
    O.bodies[sid].state.vel = Vector3(0.3, 0, -1.0)
    O.engines = _engines()
    O.dt = 0.5 * O.engines[3].stableDt()["combined"]
    b = O.bodies[sid]
    m = b.state.mass

    def momentum():
        return m * np.array(b.state.vel) + slab.momentum

    p0 = momentum()
    impulse = np.zeros(3)
    touched = 0
    for _ in range(3000):
        O.step()
        impulse -= np.array(O.forces.f(floor)) * O.dt  # the floor gets the reaction
        touched += O.engines[3].world.core.contactCounts["sphere"] > 0
    gravityImpulse = (m + slab.totalMass) * g * O.time
    scale = m * 1.0 + slab.totalMass * 9.81 * O.time
    assert touched > 10
    assert np.abs(momentum() - p0 - impulse - gravityImpulse).max() < 1e-9 * scale


def test_sliding_sphere_ends_up_rolling_at_five_sevenths(scene):
    """A sphere launched without spin slides, friction spins it up, and it rolls
    at 5/7 of its speed (solid sphere: v = v0 - mu g t, w R = 5/2 mu g t)."""
    from yade import FrictMat, Vector3, utils
    O = scene
    mat, slab, _ = _slab(O, size=(0.4, 0.1, 0.04), cells=(20, 5, 2), frictionPiece=1.0)
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=math.atan(0.3), density=2000))
    R = 0.005
    top = slab.pos[:, 2].max()
    sid = O.bodies.append(utils.sphere((-0.15, 0.003, top + mat.radius + R - 2e-6), R, material=fm))
    v0 = 0.5
    O.bodies[sid].state.vel = Vector3(v0, 0, 0)
    O.engines = _engines()
    O.dt = 0.5 * O.engines[3].stableDt()["combined"]
    mu, g = 0.3, 9.81                                  # min(atan(0.3) of the sphere, 1.0 of the slab)
    tSlide = 2 * v0 / (7 * mu * g)
    # sliding phase: friction mu m g decelerates it and spins it up (the end
    # state alone, 5/7 v0, does not depend on mu)
    O.run(int(0.5 * tSlide / O.dt), True)
    s = O.bodies[sid].state
    assert v0 - s.vel[0] == pytest.approx(mu * g * O.time, rel=0.05)
    assert s.angVel[1] * R == pytest.approx(2.5 * mu * g * O.time, rel=0.05)
    O.run(int(2.0 * tSlide / O.dt), True)
    assert s.vel[0] == pytest.approx(5 / 7 * v0, rel=0.03)
    assert s.angVel[1] * R == pytest.approx(s.vel[0], rel=0.03)  # rolling: no slip at the contact


def test_friction_work_of_a_sphere_thrown_obliquely_onto_a_slab_never_falls(scene):
    """A tester's case: a sphere thrown at 1 m/s onto a held slab, mu 0.5. When
    the tangential spring alone was under the cap and its dashpot pushed the
    trial force over it, the slip reset the spring to the full cap in one step:
    it stored more than the force had done, booked as negative friction work
    (-3.5e-5 J on the first step of contact, 20 falls in 0.25 s). The spring
    now keeps its trial stretch there; qdemFrictDissip never falls."""
    from yade import FrictMat, Vector3, utils
    O = scene
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=0.002, frictionPiece=0.5)
    T, R = 0.04, 0.01
    slab = qdem.addPiece(qdem.boxMesh((0.4, 0.2, T), (8, 4, 2)), mat, pos=(0, 0, T / 2))
    slab.dynamic = False
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=math.atan(0.5), density=2500))
    sid = O.bodies.append(utils.sphere((-0.1, 0.0, T + 0.002 + R + 0.01), R, material=fm))
    O.bodies[sid].state.vel = Vector3(1.0, 0.2, 0)
    O.engines = _engines()
    O.dt = min(0.3 * utils.PWaveTimeStep(), 0.5 * O.engines[3].stableTimeStep())
    O.trackEnergy = True
    last, falls = 0.0, []
    for _ in range(int(0.11 / O.dt)):
        O.step()
        f = O.energy["qdemFrictDissip"] if "qdemFrictDissip" in O.energy.keys() else 0.0
        if f < last - 1e-15:
            falls.append((O.iter, f - last))
        last = f
    assert last > 5e-4                                 # it slid: friction did work
    assert falls == []


def test_clump_resting_on_a_block_loads_the_floor_with_both_weights(scene):
    from yade import FrictMat, utils
    O = scene
    mat = rubber(young=1e6, viscosity=500.0, radius=0.002)
    block = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), mat, pos=(0, 0, 0.05 + 0.002))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=2000))
    z = 0.1 + 2 * 0.002 + 0.008
    clump, members = O.bodies.appendClumped([utils.sphere((x, y, z), 0.008, material=fm)
                                             for x, y in [(-0.012, -0.01), (0.014, -0.006), (0.0, 0.015)]])
    O.engines = _engines(damping=0.3)
    O.dt = 0.5 * O.engines[3].stableDt()["combined"]
    O.run(int(0.6 / O.dt), True)
    weight = (block.totalMass + O.bodies[clump].state.mass) * 9.81
    assert O.forces.f(floor)[2] == pytest.approx(-weight, rel=0.005)
    assert np.linalg.norm(O.bodies[clump].state.vel) < 1e-3
    assert O.engines[3].world.core.contactCounts["sphere"] >= 3


def test_settled_packing_stays_on_the_block_and_compresses_it_by_its_weight(scene):
    """A few thousand spheres settle on a soft block in a box of frictionless
    walls: none gets into the block, the spheres' weight reaches the block,
    and the block shortens as a uniaxially loaded bar (own weight included)."""
    from yade import FrictMat, pack, utils
    O = scene
    L, H, E, rho = 0.1, 0.08, 2e5, 1000.0
    # r = 2 mm and 10 x 10 cells: the node-floor springs and the mesh shorten
    # the block under its own weight within 2 % of the bar formula.
    mat = qdem.QdemMat(young=E, poisson=0.3, density=rho, viscosity=20.0, radius=0.002, frictionWall=0.0,
                       frictionPiece=0.5)
    block = qdem.addPiece(qdem.boxMesh((L, L, H), (10, 10, 6)), mat, pos=(0, 0, H / 2 + mat.radius))
    wm = O.materials.append(FrictMat(young=1e7, frictionAngle=0.0, density=1000))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1, material=wm))
    gap = mat.radius + 0.0005  # QDEM nodes feel walls within r: keep clear of them
    for ax in (0, 1):
        O.bodies.append(utils.wall(-L / 2 - gap, axis=ax, sense=1, material=wm))
        O.bodies.append(utils.wall(L / 2 + gap, axis=ax, sense=-1, material=wm))
    sm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.3, density=2500))
    sp = pack.SpherePack()
    zb = H + 2 * mat.radius
    sp.makeCloud((-L / 2 + 0.001, -L / 2 + 0.001, zb + 0.002), (L / 2 - 0.001, L / 2 - 0.001, zb + 0.065),
                 rMean=0.0025, rRelFuzz=0.2, seed=3)
    ids = sp.toSimulation(material=sm)
    assert len(ids) >= 2000
    O.engines = _engines(damping=0.4, checkPeriod=100)
    O.engines[3].damping = 0.3  # quasi-static: local damping on the block too
    O.dt = min(0.5 * utils.PWaveTimeStep(), 0.5 * O.engines[3].stableDt()["combined"])
    O.run(int(0.5 / O.dt), True)
    xyz = np.array([O.bodies[i].state.pos for i in ids])
    rs = np.array([O.bodies[i].shape.radius for i in ids])
    # Nobody inside or under the block, and every overlap with its surface
    # (which carries a skin of r) smaller than r.
    top = np.isclose(block.refPos[:, 2], block.refPos[:, 2].max())
    bot = np.isclose(block.refPos[:, 2], block.refPos[:, 2].min())
    over = (np.abs(xyz[:, 0]) < L / 2) & (np.abs(xyz[:, 1]) < L / 2)
    assert np.all(xyz[:, 2] > block.pos[:, 2].max())
    assert np.all(xyz[over, 2] - rs[over] > block.pos[top, 2].min())
    W = sum(O.bodies[i].state.mass for i in ids) * 9.81
    onBlock = O.engines[3].world.core.sphereForceTorque()[:, 2].sum()
    assert onBlock == pytest.approx(W, rel=0.05)
    # Shortening: mean top height drop vs (load/A + own weight/2) * H / E.
    shortening = (block.refPos[top, 2].mean() - block.refPos[bot, 2].mean()) - \
        (block.pos[top, 2].mean() - block.pos[bot, 2].mean())
    expected = (W / (L * L) + 0.5 * rho * 9.81 * H) * H / E
    assert shortening == pytest.approx(expected, rel=0.05)


def test_only_near_spheres_are_listed_and_an_erased_one_lets_go(scene):
    from yade import FrictMat, utils
    O = scene
    mat = rubber(young=1e6, viscosity=500.0, radius=0.002)
    block = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.05 + 0.002))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=2000))
    onTop = O.bodies.append(utils.sphere((0.01, 0.0, 0.1 + 0.004 + 0.01), 0.01, material=fm))
    far = [O.bodies.append(utils.sphere((1.0 + 0.05 * k, 0.5, 0.01), 0.01, material=fm))
           for k in range(10)]  # far away, resting on the floor
    O.engines = _engines(damping=0.3)
    qe = O.engines[3]
    qe.damping = 0.3  # quasi-static
    O.dt = 0.5 * qe.stableDt()["combined"]
    O.run(int(0.4 / O.dt), True)
    assert qe.world.core.nSpheres == 1
    assert qe.world.core.contactCounts["sphere"] >= 1
    proxies = qe.proxyIds()
    assert len(proxies) == 1 and type(O.bodies[proxies[0]].shape).__name__ == "Tetra"
    assert not O.bodies[proxies[0]].dynamic
    farWeight = sum(O.bodies[i].state.mass for i in far) * 9.81  # they load the floor too
    load = (block.totalMass + O.bodies[onTop].state.mass) * 9.81 + farWeight
    assert O.forces.f(floor)[2] == pytest.approx(-load, rel=0.01)
    O.bodies.erase(onTop)
    O.step()
    assert qe.world.core.contactCounts["sphere"] == 0 and qe.world.core.nSpheres == 0
    O.run(int(0.2 / O.dt), True)
    assert O.forces.f(floor)[2] == pytest.approx(-block.totalMass * 9.81 - farWeight, rel=0.01)


def test_block_dropped_onto_a_sphere_bed_comes_to_rest_on_it(scene):
    """The block falls far more than its proxy's margin: the proxy follows it
    and the collider lists the bed in time."""
    from yade import FrictMat, utils
    O = scene
    mat = rubber(young=1e6, viscosity=500.0, radius=0.002)
    block = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.05), (4, 4, 2)), mat, pos=(0, 0, 0.3))
    fm = O.materials.append(FrictMat(young=1e7, poisson=0.3, frictionAngle=0.5, density=2000))
    R = 0.01
    bed = [O.bodies.append(utils.sphere((x, y, R), R, material=fm, fixed=True))
           for x in np.arange(-0.2, 0.201, 2 * R) for y in np.arange(-0.2, 0.201, 2 * R)]
    O.engines = _engines()
    qe = O.engines[3]
    O.dt = 0.5 * qe.stableDt()["combined"]
    O.run(int(0.3 / O.dt), True)  # falls, hits the bed, bounces
    qe.damping = 0.3  # then settles quickly
    O.run(int(0.6 / O.dt), True)
    bottom = block.pos[:, 2].min()
    assert bottom > 2 * R  # resting on the bed, not through it
    assert np.abs(block.velocity).max() < 0.02
    assert qe._spheres.refreshes >= 2
    weight = block.totalMass * 9.81
    assert qe.world.core.sphereForceTorque()[:, 2].sum() == pytest.approx(-weight, rel=0.02)
    assert 16 <= qe.world.core.nSpheres < len(bed)  # the spheres under the block, not the whole bed


def test_qdem_threads_leave_yade_own_thread_count_alone(scene):
    """QDEM on 2 threads inside `yade -n` (1 thread): YADE's InteractionLoop must
    keep its own count (its force buffers are sized for it) — this crashed
    when QDEM set the process-wide OpenMP count."""
    import ctypes
    from yade import FrictMat, utils
    O = scene
    qdem._core.setThreads(2)
    gomp = ctypes.CDLL("libgomp.so.1")
    before = gomp.omp_get_max_threads()
    mat = rubber(young=1e6, viscosity=500.0, radius=0.002)
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.05 + 0.002))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=2000))
    for k in range(40):  # a heap of touching spheres beside the block: real YADE contacts
        O.bodies.append(utils.sphere((0.1 + 0.019 * (k % 8), 0.019 * (k // 8), 0.01), 0.01, material=fm))
    O.engines = _engines()
    O.dt = 0.5 * O.engines[3].stableDt()["combined"]
    O.run(300, True)
    assert gomp.omp_get_max_threads() == before
    assert qdem._core.getThreads() == 2
    assert len([i for i in O.interactions if i.isReal]) > 20


def test_sphere_bounces_off_a_piece_that_is_not_dynamic(scene):
    # A held piece (Piece.dynamic = False) is a fixed body for spheres too:
    # the sphere comes back up, nothing of the slab moves, the slab stays held.
    from yade import FrictMat, Vector3, utils
    O = scene
    mat, slab, _ = _slab(O)
    slab.dynamic = False
    x0 = slab._nodes("pos").copy()
    fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=100))
    R = 0.005
    topZ = slab.refPos[:, 2].max()
    node = np.flatnonzero(np.isclose(slab.refPos[:, 2], topZ) & np.isclose(slab.refPos[:, 0], 0.02)
                          & np.isclose(slab.refPos[:, 1], 0.04))[0]   # straight below the sphere
    sid = O.bodies.append(utils.sphere((0.02, 0.04, topZ + mat.radius + R + 1e-4), R, material=fm))
    O.bodies[sid].state.vel = Vector3(0, 0, -1.0)
    O.engines = _engines(gravity=(0, 0, 0))
    O.dt = 0.25 * O.engines[3].stableDt()["combined"]
    _runThroughOneImpact(O)
    # The held slab does not move: the sphere alone on the law's spring and
    # dashpot (the dashpot from the reduced mass with the contact node).
    kn = 2 * (1e6 * R) * (mat.young * mat.radius) / (1e6 * R + mat.young * mat.radius)
    predicted = _lawRebound(kn, O.bodies[sid].state.mass, slab.mass[node], mat.restitution)
    assert O.bodies[sid].state.vel[2] == pytest.approx(predicted, rel=0.02)
    assert np.array_equal(slab._nodes("pos"), x0) and slab.asleep and not slab.dynamic


@pytest.mark.parametrize("speed", [5.0, 500.0])
def test_a_sphere_too_fast_for_the_step_near_a_piece_stops_the_run(scene, speed):
    """A 2 cm sphere at 500 m/s moves 8 cm a step, more than twice its
    contact reach: before, it went through a 0.1 m plate (ending 1 m below it, still
    falling) without a word.  Now the step in which it comes next to the piece
    so fast stops, naming the step that would do; at 5 m/s it bounces."""
    from yade import Vector3, utils
    O = scene
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=700, radius=0.01)
    plate = qdem.addPiece(qdem.boxMesh((0.4, 0.4, 0.1), (4, 4, 1)), mat)
    plate.blocked[:] = 7
    sid = O.bodies.append(utils.sphere((0, 0, 0.3), 0.02))
    O.bodies[sid].state.vel = Vector3(0, 0, -speed)
    O.engines = _engines(gravity=(0, 0, 0))
    O.dt = 0.5 * O.engines[3].stableTimeStep()
    steps = int(0.6 / speed / O.dt) + 10
    if speed > 100:
        assert speed * O.dt > 2 * 0.03  # the case: more than twice its contact reach a step
        with pytest.raises(qdem.StabilityError, match=r"YADE sphere %d moves %s m per step \(500 m/s.* next to "
                                                      r"piece 0, more than its contact reach 0.03 m.*Lower O.dt below "
                                                      r"6e-05 s" % (sid, re.escape("%.6g" % (speed * O.dt)))):
            O.run(steps, True)
        assert O.bodies[sid].state.pos[2] > 0.0           # stopped before it went through
    else:
        O.run(steps, True)
        assert O.bodies[sid].state.vel[2] > 0             # bounced


PROXY_SCENE = """
import warnings, numpy as np, qdem
from yade import (O, utils, FrictMat, Bo1_Sphere_Aabb, Bo1_Wall_Aabb, ForceResetter, Ig2_Sphere_Sphere_ScGeom,
                  Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_FrictPhys,
                  Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)
def engines():
    return [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
            InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                            [Ip2_FrictMat_FrictMat_FrictPhys()], [Law2_ScGeom_FrictPhys_CundallStrack()]),
            qdem.QdemEngine(label="qe", damping=0.3), NewtonIntegrator(gravity=(0, 0, -9.81))]
mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=500, radius=0.002)
block = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.052))
fm = O.materials.append(FrictMat(young=1e6, poisson=0.3, frictionAngle=0.5, density=2000))
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
ball = O.bodies.append(utils.sphere((0.01, 0, 0.12), 0.01, material=fm))
O.engines = engines()
O.dt = 0.5 * qe.stableDt()["combined"]
O.run(200, True)
"""


def _yadeScript(tmp_path, code):
    import os
    import subprocess
    import textwrap
    path = tmp_path / "s.py"
    path.write_text(textwrap.dedent(code))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    return subprocess.run(["timeout", "300", "yade", "-n", "-x", str(path)], cwd=str(tmp_path), env=env,
                          capture_output=True, text=True)


def test_an_erased_proxy_is_placed_again_and_the_sphere_stays_on_the_piece(tmp_path):
    """A clean-up loop that erases bodies may erase the proxy too: YADE aborted
    (a null body in O.interactions.withBodyAll)."""
    r = _yadeScript(tmp_path, PROXY_SCENE + """
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    for b in list(O.bodies):
        if b.id in qe.proxyIds():
            O.bodies.erase(b.id)
    O.run(int(0.4 / O.dt), True)
assert any("proxy bodies" in str(w.message) for w in caught), [str(w.message) for w in caught]
z = O.bodies[ball].state.pos[2]
assert 0.1 + 0.004 + 0.009 < z < 0.1 + 0.004 + 0.011, z   # resting on the block's top
load = (block.totalMass + O.bodies[ball].state.mass) * 9.81
assert abs(O.forces.f(floor)[2] + load) < 0.01 * load, (O.forces.f(floor)[2], load)
print("OK")
""")
    assert r.returncode == 0 and "OK" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]


def test_cleared_bodies_get_new_proxies_and_a_user_body_at_an_old_proxy_id_is_left_alone(tmp_path):
    """After O.bodies.clear() the engine took a user's sphere, appended at the
    old proxy id, for its proxy (teleported it into the piece), and a sphere
    dropped on the piece fell through it."""
    r = _yadeScript(tmp_path, PROXY_SCENE + """
old = qe.proxyIds()
O.bodies.clear()
floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
ids = [O.bodies.append(utils.sphere((0.5 + 0.1 * k, 0, 0.01), 0.01, material=fm)) for k in range(3)]
ball = O.bodies.append(utils.sphere((0.01, 0, 0.15), 0.01, material=fm))
assert old[0] in ids
with warnings.catch_warnings(record=True):
    warnings.simplefilter("always")
    O.run(int(0.5 / O.dt), True)
assert not set(qe.proxyIds()) & set(ids)
for k, i in enumerate(ids):
    assert np.allclose(O.bodies[i].state.pos, (0.5 + 0.1 * k, 0, 0.01), atol=1e-4), O.bodies[i].state.pos
z = O.bodies[ball].state.pos[2]
assert 0.1 + 0.004 + 0.009 < z < 0.1 + 0.004 + 0.011, z
print("OK")
""")
    assert r.returncode == 0 and "OK" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]


def _pushedSphere(O, fric=0.5, material=None):
    """A sphere (rotations blocked) resting on a slab, pushed sideways by 0.2 of
    its weight: it sticks at friction 0.5.  Returns (sphere, its x)."""
    from yade import FrictMat, PyRunner, utils
    _slab(O, young=1e7, frictionPiece=0.5)
    m = material or FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=math.atan(fric))
    s = O.bodies.append(utils.sphere((0, 0, 0.04 + 2 * 0.002 + 0.01 + 1e-4), 0.01, material=m))
    O.bodies[s].state.blockedDOFs = "XYZ"
    O.engines = _engines() + [PyRunner(command="O.forces.addF(%d, (0.2 * 9.81 * O.bodies[%d].state.mass, 0, 0))"
                                       % (s, s), iterPeriod=1)]
    O.engines = O.engines[:-2] + [O.engines[-1], O.engines[-2]]  # (the push before NewtonIntegrator)
    O.dt = 0.5 * O.engines[3].stableTimeStep()
    O.run(int(0.1 / O.dt), True)
    return O.bodies[s], O.bodies[s].state.pos[0]


@pytest.mark.parametrize("how", ["setContactFriction", "material", "newMaterial"])
def test_a_sphere_made_frictionless_mid_run_slides(scene, how):
    """Sphere properties were read once and kept: after utils.setContactFriction(0)
    (the triaxial 'compact without friction' recipe) or a material edit the
    sphere stayed stuck.  Now it slides at 0.2 g."""
    from yade import FrictMat, utils
    O = scene
    b, x0 = _pushedSphere(O)
    assert abs(b.state.vel[0]) < 1e-3, "friction 0.5 holds a push of 0.2 of the weight"
    if how == "setContactFriction":
        utils.setContactFriction(0.0)
    elif how == "material":
        b.material.frictionAngle = 0.0
    else:
        b.material = FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=0.0)
    T = 0.1
    O.run(int(T / O.dt), True)
    assert b.state.vel[0] == pytest.approx(0.2 * 9.81 * T, rel=0.03)


def test_a_grown_sphere_rests_at_its_new_radius(scene):
    """utils.growParticles changed the radius YADE uses but not QDEM's copy: the
    sphere sat a centimetre inside the piece."""
    from yade import FrictMat, utils
    O = scene
    mat, slab, floor = _slab(O, young=1e7)
    s = O.bodies.append(utils.sphere((0, 0, 0.04 + 2 * 0.002 + 0.01), 0.01,
                                     material=FrictMat(young=1e7, poisson=0.3, density=2600, frictionAngle=0.5)))
    O.engines = _engines()
    O.dt = 0.5 * O.engines[3].stableTimeStep()
    O.run(int(0.1 / O.dt), True)
    utils.growParticles(1.5, updateMass=True)
    O.dt = 0.5 * O.engines[3].stableTimeStep()
    O.run(int(0.4 / O.dt), True)
    top = slab.pos[:, 2].max()
    assert O.bodies[s].shape.radius == pytest.approx(0.015)
    assert O.bodies[s].state.pos[2] - top > 0.015 + 0.002 - 0.003, "the sphere rests on the piece, not inside it"


def test_a_sphere_material_without_friction_angle_takes_the_piece_friction(scene):
    """ElastMat has no frictionAngle: as for walls, the piece's friction alone
    (it was taken as frictionless for spheres)."""
    from yade import ElastMat
    O = scene
    b, x0 = _pushedSphere(O, material=ElastMat(young=1e7, poisson=0.3, density=2600))
    O.run(int(0.1 / O.dt), True)
    assert abs(b.state.pos[0] - x0) < 1e-3, "frictionPiece 0.5 holds a push of 0.2 of the weight"


def test_a_sphere_friction_angle_in_degrees_is_refused_naming_radians(scene):
    from yade import FrictMat, utils
    O = scene
    _slab(O)
    O.bodies.append(utils.sphere((0, 0, 0.06), 0.01, material=FrictMat(young=1e7, frictionAngle=30)))
    O.engines = _engines()
    with pytest.raises(ValueError, match="frictionAngle = 30.0 rad is not in"):
        O.dt = O.engines[3].stableTimeStep()


@pytest.mark.parametrize("case", ["soft", "placedInside"])
def test_a_sphere_inside_a_piece_beyond_the_reach_stops_the_run(scene, case):
    """A sphere whose contact was too soft for its weight sank through the
    block and on through the floor, and one appended deep inside a piece
    stayed there, both with no word: out of every contact's reach."""
    from yade import FrictMat, utils
    O = scene
    mat, slab, floor = _slab(O, young=1e7, size=(0.2, 0.2, 0.1), cells=(4, 4, 2), radius=0.005)
    top = slab.pos[:, 2].max()
    young, z = (2e2, top + 0.005 + 0.02 + 0.005) if case == "soft" else (1e7, top - 0.05)
    O.bodies.append(utils.sphere((0.01, 0.01, z), 0.02 if case == "soft" else 0.01,
                                 material=FrictMat(young=young, poisson=0.3, density=2600, frictionAngle=0.5)))
    O.engines = _engines()
    O.dt = 0.5 * O.engines[3].stableTimeStep()
    with pytest.raises(qdem.StabilityError, match=r"YADE sphere #\d+ .* is inside piece 0.*beyond the contact's "
                                                  r"reach.*stiffer material"):
        O.run(int(0.6 / O.dt), True)
