"""YADE walls, boxes and facets as obstacles: what their own body brings to the
contact.  Found by a tester (2026-11): a facet's friction angle was ignored
(a frictionless slope held a block), a light dynamic box was launched by the
contact springs (the stable step ignored its mass), and a facet whose edge hung
just above a slab was taken for one cutting through it (its infinite plane was
checked, not the triangle)."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber


def _engines(gravity=(0, 0, -9.81)):
    from yade import ForceResetter, NewtonIntegrator
    return [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=gravity, damping=0)]


def _rotY(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


# --- friction of the obstacle's material --------------------------------------

def _facetSlope(O, theta, frictionAngle, frictionWall):
    """A 0.2 m block on a square of two fixed facets tilted by theta about y,
    whose material has frictionAngle; returns (block, down-slope unit vector)."""
    from yade import FrictMat, Vector3, utils
    R = _rotY(theta)
    n = R @ (0, 0, 1.0)
    g = np.array([0, 0, -9.81])
    down = g - (g @ n) * n
    down /= np.linalg.norm(down)
    mat = O.materials.append(FrictMat(young=1e9, poisson=0.3, frictionAngle=frictionAngle, density=1000))
    pts = [R @ np.array(p) for p in [(-1.5, -1.5, 0), (1.5, -1.5, 0), (1.5, 1.5, 0), (-1.5, 1.5, 0)]]
    for tri in [(0, 1, 2), (0, 2, 3)]:
        O.bodies.append(utils.facet([Vector3(*pts[k]) for k in tri], fixed=True, material=mat))
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), rubber(viscosity=2000.0, frictionWall=frictionWall),
                          pos=tuple(0.105 * n), ori=((0, 1, 0), theta))
    O.engines = _engines()
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    return block, down


def _slideAcceleration(O, block, down):
    O.run(int(0.1 / O.dt), True)                    # settle onto the slope
    t1, v1 = O.time, block.velocity @ down
    O.run(int(0.2 / O.dt), True)
    return (block.velocity @ down - v1) / (O.time - t1)


def test_block_slides_freely_on_a_frictionless_facet_slope(scene):
    """Facets of frictionAngle 0 under a block of frictionWall 0.5, tilted 20
    degrees: the smaller friction (none) acts, the block slides at g sin(theta).
    (It used to stay put: frictionWall alone held it.)"""
    theta = math.radians(20)
    block, down = _facetSlope(scene, theta, 0.0, 0.5)
    assert _slideAcceleration(scene, block, down) == pytest.approx(9.81 * math.sin(theta), rel=0.01)


def test_the_facets_friction_acts_when_smaller_than_frictionWall(scene):
    """frictionAngle atan(0.3) against frictionWall 0.5 on a 25 degree slope
    (steeper than atan 0.3 = 16.7 degrees): g (sin - 0.3 cos)."""
    theta = math.radians(25)
    block, down = _facetSlope(scene, theta, math.atan(0.3), 0.5)
    expected = 9.81 * (math.sin(theta) - 0.3 * math.cos(theta))
    assert _slideAcceleration(scene, block, down) == pytest.approx(expected, rel=0.02)


@pytest.mark.parametrize("how", ["edit", "newMaterial"])
def test_a_slope_made_frictionless_mid_run_lets_the_block_slide(scene, how):
    """An obstacle's material was read once when QDEM first saw the body: a
    slope whose friction the script set to 0 mid-run still held the block."""
    from yade import FrictMat
    O = scene
    theta = math.radians(20)
    block, down = _facetSlope(O, theta, math.atan(0.8), 0.8)
    O.run(int(0.1 / O.dt), True)
    assert abs(block.velocity @ down) < 0.02, "friction 0.8 holds the block (sliding: 0.34 m/s by now)"
    facets = [b for b in O.bodies if b is not None and type(b.shape).__name__ == "Facet"]
    for b in facets:
        if how == "edit":
            b.material.frictionAngle = 0.0
        else:
            b.material = FrictMat(frictionAngle=0.0)
    assert _slideAcceleration(O, block, down) == pytest.approx(9.81 * math.sin(theta), rel=0.02)


def test_a_bad_friction_angle_is_refused_naming_the_body(scene):
    from yade import FrictMat, utils
    O = scene
    mat = O.materials.append(FrictMat(frictionAngle=2.0))
    bid = O.bodies.append(utils.wall(0, axis=2, sense=1, material=mat))
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 0.2))
    O.engines = _engines()
    with pytest.raises(ValueError, match=r"YADE body %d \(Wall\): its material's frictionAngle = 2.0 rad is not "
                                         r"in \[0, pi/2\)" % bid):
        O.engines[1].stableTimeStep()


# --- a facet beside a piece is not inside it ------------------------------------

def _fence(O, gap):
    """A 0.2 x 0.2 x 0.05 m slab on a floor under a vertical facet (a fence in the
    plane x = 0.024, between two columns of nodes) whose lower edge is gap above
    the slab's top (gap < 0: in the slab)."""
    from yade import Vector3, utils
    slab = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.05), (8, 8, 2)), rubber(young=1e6, viscosity=50.0),
                         pos=(0, 0, 0.025 + 0.005))
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    z = 0.055 + gap
    fence = O.bodies.append(utils.facet([Vector3(0.024, -0.3, z), Vector3(0.024, 0.3, z), Vector3(0.024, 0, 0.4)],
                                        fixed=True))
    O.engines = _engines()
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    return slab, floor, fence


def test_a_facet_whose_edge_hangs_just_above_a_piece_is_not_refused(scene):
    """Its lower edge 3 mm (< r = 5 mm) above the slab: the nodes beyond its
    plane are below the triangle, not behind it (it was refused as "58 of its
    194 surface nodes are past its surface, the deepest by 0.0927 m").  The
    edge is within the contact reach of the top nodes next to it: it presses
    the slab onto the floor, which carries that and the weight, and holds it
    by friction against the edge's sideways push."""
    O = scene
    slab, floor, fence = _fence(O, 0.003)
    c0 = slab.centroid
    O.run(int(0.3 / O.dt), True)
    weight = slab.totalMass * 9.81
    onFloor, onFence = np.array(O.forces.f(floor)), np.array(O.forces.f(fence))
    assert onFence[2] > weight                                   # pressed down: a contact, not a refusal
    assert -onFloor[2] == pytest.approx(weight + onFence[2], rel=0.02)
    assert onFloor[0] == pytest.approx(-onFence[0], rel=0.05)
    assert np.linalg.norm(slab.centroid - c0) < 1e-3 and np.abs(slab.vel).max() < 0.01


@pytest.mark.parametrize("gap", [-0.003, -0.03])
def test_a_facet_cutting_into_a_piece_is_still_refused(scene, gap):
    """The same fence with its edge 3 mm or 3 cm inside the slab: the top nodes
    beyond x = 0.024 are behind the triangle."""
    O = scene
    fence = _fence(O, gap)[2]
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body %d \(facet\): \d+ of its 194 "
                                         r"surface nodes are past its surface, the deepest by 0.076 m" % fence):
        O.engines[1].stepOnce()


# --- a dynamic obstacle's mass in the stable step ---------------------------------

def _boxOnBlock(O, rho):
    """A 0.1 x 0.1 x 0.02 m dynamic YADE box of density rho (2 g at 10 kg/m^3)
    released 2 mm above a 0.2 x 0.2 x 0.1 m block on the floor."""
    from yade import FrictMat, utils
    bm = O.materials.append(FrictMat(young=1e9, poisson=0.3, frictionAngle=0.5, density=rho))
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.1), (4, 4, 2)), rubber(young=1e6, viscosity=100.0),
                          pos=(0, 0, 0.055))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    box = O.bodies.append(utils.box((0, 0, 0.105 + 0.005 + 0.01 + 0.002), (0.05, 0.05, 0.01), material=bm,
                                    fixed=False))
    O.engines = _engines()
    return block, box


def _boxEnergy(O, box):
    s = O.bodies[box].state
    w, inertia = np.array(s.angVel), np.array(s.inertia)     # (principal; the box barely turns)
    return 0.5 * s.mass * s.vel.squaredNorm() + 0.5 * (inertia * w) @ w + s.mass * 9.81 * s.pos[2]


@pytest.mark.parametrize("rho", [10.0, 1000.0])
def test_a_light_dynamic_box_dropped_on_a_block_gains_no_energy(scene, rho):
    """The stable step counts the box's mass on the node springs: with O.dt =
    0.8 stableTimeStep() it lands and rests.  (A 2 g box was kicked to 4.9 m/s
    in one step, 800 times its energy: the dashpots sized for the nodes' mass,
    and O.dt 30 times the box's limit.)"""
    O = scene
    block, box = _boxOnBlock(O, rho)
    limit = O.engines[1].stableDt()
    assert "dynamic box (YADE body %d, mass %g kg" % (box, O.bodies[box].state.mass) in limit["limitedBy"]
    assert limit["obstacle"] == limit["combined"]
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    e0 = _boxEnergy(O, box)
    vmax = 0.0
    for _ in range(30):
        O.run(int(0.005 / O.dt), True)
        vmax = max(vmax, O.bodies[box].state.vel.norm())
        assert _boxEnergy(O, box) <= e0 + 1e-9
    assert vmax < 0.25                                           # free fall from 2 mm: 0.2 m/s
    assert O.bodies[box].state.vel.norm() < 0.01                 # at rest on the block
    assert O.bodies[box].state.pos[2] == pytest.approx(0.105 + 0.005 + 0.01, abs=1e-3)


def test_an_O_dt_above_a_dynamic_box_limit_is_refused_naming_it_and_the_fix(scene):
    O = scene
    block, box = _boxOnBlock(O, 10.0)
    limit = O.engines[1].stableTimeStep()
    O.dt = 1.05 * limit
    with pytest.raises(qdem.StabilityError, match=r"O.dt=.* exceeds the stable time step .*limited by the dynamic "
                                                  r"box \(YADE body %d, mass 0.002 kg.*Lower O.dt, make the body "
                                                  r"heavier, or fix it \(fixed=True" % box):
        O.engines[1].stepOnce()


def test_a_dynamic_facet_without_mass_is_refused(scene):
    """utils.facet(..., fixed=False) has no mass: YADE would give it an infinite
    acceleration (NaN) at its first touch."""
    from yade import utils
    O = scene
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber(), pos=(0, 0, 0.3))
    f = O.bodies.append(utils.facet([(-1, -1, 0), (1, -1, 0), (0, 1, 0)], fixed=False))
    O.engines = _engines()
    # stableTimeStep() returned 0 (O.dt = 0.8 * 0 then failed naming nothing): it names the facet
    with pytest.raises(qdem.StabilityError, match=r"dynamic facet \(YADE body %d.*fixed=True" % f):
        O.engines[1].stableTimeStep()
    O.dt = 1e-6
    with pytest.raises(qdem.StabilityError, match=r"dynamic facet \(YADE body %d, mass 0 kg.*give the body a "
                                                  r"mass and moment of inertia" % f):
        O.engines[1].stepOnce()


def test_a_dynamic_obstacle_pressed_on_more_springs_than_foreseen_stops_the_run():
    """Each step checks the springs actually on a dynamic obstacle: a 1 g box
    pressed 3 mm into a cube on every side it touches, stepped at 100 times its
    limit, is named with the step that would do."""
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), rubber(radius=0.005))
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.halfExtents = 1, 7, (0.1, 0.1, 0.01)
    o.invMass, o.invInertia = 1000.0, 0.0
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0.05 + 0.01 + 0.002, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]], dtype=float))
    limit = w.stableDt()["obstacle"]
    assert 0 < limit < w.stableDt()["elastic"]
    w.core.step(0.5 * limit, 1)                                  # below it: steps
    with pytest.raises(qdem.StabilityError, match=r"the dynamic box \(YADE body 7, mass 0.001 kg\) is touched by "
                                                  r"25 surface nodes: .* stable time step .* below O.dt"):
        w.core.step(100 * limit, 1)


def test_what_yade_moves_is_what_the_limit_counts(scene):
    """A fixed body and one with every DOF blocked do not move: no limit.  Free
    translations only: 1/m alone.  A clump member: its clump's mass and
    inertia, and its distance from the clump's centre."""
    from yade import utils
    from qdem.yade import glue as yadeglue
    O = scene
    ids = [O.bodies.append(utils.box((0.3 * i, 0, 1), (0.05, 0.05, 0.01), fixed=(i == 0))) for i in range(4)]
    O.bodies[ids[1]].state.blockedDOFs = "xyzXYZ"
    O.bodies[ids[2]].state.blockedDOFs = "XYZ"
    clump = O.bodies.clump([ids[3], O.bodies.append(utils.box((1.3, 0, 1), (0.05, 0.05, 0.01)))])
    obstacles = {o.bodyId: o for o in yadeglue.scanObstacles(O)[0]}
    m, cs = O.bodies[ids[2]].state.mass, O.bodies[clump].state
    assert (obstacles[ids[0]].invMass, obstacles[ids[0]].invInertia) == (0, 0)
    assert (obstacles[ids[1]].invMass, obstacles[ids[1]].invInertia) == (0, 0)
    assert (obstacles[ids[2]].invMass, obstacles[ids[2]].invInertia) == (pytest.approx(1 / m), 0)
    o = obstacles[ids[3]]
    assert o.invMass == pytest.approx(1 / cs.mass) and o.invInertia == pytest.approx(1 / min(cs.inertia))
    assert o.armOffset == pytest.approx((O.bodies[ids[3]].state.pos - cs.pos).norm())


@pytest.mark.parametrize("kind", ["wall", "facet", "box"])
def test_a_piece_placed_flush_on_a_floor_is_warned_of_and_one_placed_r_above_is_not(scene, kind):
    """A block placed with its mesh face on the floor (centre at half its
    height, the natural YADE placement) has every bottom node's spring
    compressed by a whole radius: it was thrown up at ~1.2 m/s with no word.
    Now a RuntimeWarning names the stored energy and the fix (r higher);
    placed r higher it rests, and nothing is said."""
    import warnings
    from yade import utils
    O = scene
    mat = rubber(radius=0.01)

    def floor():
        if kind == "wall":
            return utils.wall(0, axis=2, sense=1)
        if kind == "facet":
            return utils.facet([(-1, -1, 0), (1, -1, 0), (0, 1, 0)], fixed=True)
        return utils.box((0, 0, -0.05), (1, 1, 0.05), fixed=True)

    O.bodies.append(floor())
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), mat, pos=(0, 0, 0.1))
    O.engines = _engines()
    O.dt = 0.5 * O.engines[-2].stableTimeStep()
    with pytest.warns(RuntimeWarning, match=r"piece 0 starts pressed 0.01 m \(100 % of its node radius.*place it "
                                            r"0.01 m higher"):
        O.run(1, True)
    O.reset()
    O.bodies.append(floor())
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), mat, pos=(0, 0, 0.1 + mat.radius))
    O.engines = _engines()
    O.dt = 0.5 * O.engines[-2].stableTimeStep()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        O.run(400, True)
    assert block.velocity[2] < 0.05



def test_a_block_hitting_a_thin_box_bounces_as_on_a_thick_one(scene):
    """A node inside a YADE Box was pushed out through the nearest face: one
    pushed more than half way into a 4 mm plate (a block at 8 m/s, contact
    radius 1 cm) went out through its far face, and the block fell through
    the floor with no word (a tester).  Side memory keeps the face the
    contact came in by: the thin plate throws the block back as a 10 cm box
    does."""
    O = scene
    from yade import utils
    out = {}
    for thickness in (0.004, 0.1):
        O.reset()
        mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=20, radius=0.01, restitution=0.5)
        block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.111), vel=(0, 0, -8))
        O.bodies.append(utils.box(center=(0, 0, -thickness / 2), extents=(1, 1, thickness / 2), fixed=True))
        O.engines = _engines()
        O.dt = 0.5 * O.engines[1].stableTimeStep()
        O.run(int(0.06 / O.dt), True)
        out[thickness] = (block.velocity[2], block.centroid[2], np.min(block.pos[:, 2]))
    thin, thick = out[0.004], out[0.1]
    assert thick[0] > 5.0  # thrown back up
    assert thin[0] == pytest.approx(thick[0], rel=1e-3)
    assert thin[1] == pytest.approx(thick[1], rel=1e-3)
    assert thin[2] > 0


def _facetStrips(O, edges, y=1.0):
    """A flat floor at z = 0 of rectangular strips between the given x, two facets each."""
    from yade import Vector3, utils
    ids = []
    for x0, x1 in zip(edges[:-1], edges[1:]):
        P = [Vector3(x0, -y, 0), Vector3(x1, -y, 0), Vector3(x1, y, 0), Vector3(x0, y, 0)]
        ids += [O.bodies.append(utils.facet([P[0], P[1], P[2]], fixed=True)),
                O.bodies.append(utils.facet([P[0], P[2], P[3]], fixed=True))]
    return ids


@pytest.mark.parametrize("floor", ["facets", "boxes"])
def test_a_seam_of_a_flat_floor_made_of_several_bodies_is_not_felt(scene, floor):
    """Each obstacle acted for itself: a node near the seam of two facets (or
    two boxes side by side) was pushed by both, the seam was stiffer, and a
    block resting across a seam under a row of its nodes stood tilted
    (dz/dx = 2.5e-4) and 19 % less deep (a tester).  One surface is now one
    touch: the block rests level, as deep as on one box."""
    O = scene
    from yade import utils
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=0.01, restitution=0.2)
    result = {}
    for kind in ("one box", floor):
        O.reset()
        block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.11))
        if kind == "one box":
            O.bodies.append(utils.box(center=(0, 0, -0.05), extents=(1, 1, 0.05), fixed=True))
        elif kind == "facets":
            _facetStrips(O, [-1, 0.05, 1])  # the seam under the row of nodes at x = 0.05
        else:
            O.bodies.append(utils.box(center=(-0.475, 0, -0.05), extents=(0.525, 1, 0.05), fixed=True))
            O.bodies.append(utils.box(center=(0.525, 0, -0.05), extents=(0.475, 1, 0.05), fixed=True))
        O.engines = _engines()
        O.dt = 0.8 * O.engines[1].stableTimeStep()
        O.run(int(0.6 / O.dt), True)
        p = block.pos
        bottom = p[p[:, 2] < p[:, 2].min() + 1e-3]
        tilt = np.polyfit(bottom[:, 0], bottom[:, 2], 1)[0]
        result[kind] = (tilt, bottom[:, 2].min())
    assert abs(result[floor][0]) < 1e-9
    assert result[floor][1] == pytest.approx(result["one box"][1], rel=1e-6)


def test_a_frictionless_block_slides_over_facet_seams_without_slowing(scene):
    """On a floor of 5 cm facet strips a frictionless block sliding at 0.5 m/s
    lost 7 % of its speed in a second (the seams pushed it back); on one box
    it keeps it (a tester)."""
    O = scene
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=0.01, restitution=0.2,
                       frictionWall=0.0)
    block = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), mat, pos=(0, 0, 0.10969))
    _facetStrips(O, np.arange(-0.3, 0.8001, 0.05))
    O.engines = _engines()
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    O.run(int(0.2 / O.dt), True)
    block.vel[:, 0] += 0.5
    O.run(int(0.5 / O.dt), True)
    assert block.velocity[0] == pytest.approx(0.5, abs=2e-4)


@pytest.mark.parametrize("wallYoung, warned", [(1e4, True), (1e7, False)])
def test_a_piece_sinking_into_a_much_softer_yade_body_is_warned_of(scene, wallYoung, warned):
    """The contact takes the softer of the two stiffnesses: a large or stiff
    piece on a body left with YADE's default material (E = 1e7) sank most of
    its nodes' radius into it, silently (a 100 m piece, E = 5e8: 4.1 m of
    5 m; a tester).  Named once, with the fix; not for a body as stiff as
    the piece."""
    import warnings
    O = scene
    from yade import FrictMat, utils
    mat = rubber(viscosity=200.0)  # E = 1e7
    qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (3, 3, 3)), mat, pos=(0, 0, 0.111))
    soft = O.materials.append(FrictMat(young=wallYoung, poisson=0.3, frictionAngle=0.5))
    O.bodies.append(utils.wall(0, axis=2, sense=1, material=soft))
    O.engines = _engines()
    O.dt = 0.8 * O.engines[1].stableTimeStep()
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        O.run(int(0.5 / O.dt), True)
    said = [str(w.message) for w in got if "times softer than the piece" in str(w.message)]
    assert len(said) == (1 if warned else 0), said
    if warned:
        assert "YADE body 0 (wall)" in said[0] and "FrictMat(young=1e+07)" in said[0]
