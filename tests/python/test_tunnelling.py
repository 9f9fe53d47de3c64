"""No tunnelling (issue 12, item 5).  Soft cubes hitting each other or a floor
head-on at 5, 25 and 50 m/s: where the contact law can stop them (stopping
distance v sqrt(m_node/kn) below half the thinner piece's thickness) they
rebound on their own sides, momentum conserved and no energy gained; where
it cannot, the run stops with a StabilityError naming the speed and the fix.
Before the fix, two such cubes at 25 m/s passed through each other."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber

L = 0.1


def _mech(e):
    return e["kinetic"] + e["elastic"] + e["contactElastic"] + e["gravity"]


def _pair(speed, young, ori=None, offset=(0.01, 0.0), radius=2e-3):
    w = qdem.World()
    mat = rubber(radius=radius, viscosity=100.0, young=young)
    a = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(-0.06, 0, 0), vel=(speed, 0, 0))
    b = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(0.06, offset[0], offset[1]), ori=ori,
                   vel=(-speed, 0, 0))
    return w, a, b, mat


def _stopping(speed, mat, piece):
    """v sqrt(m/kn) of the heaviest surface node hitting at the closing speed
    (kn = E r of two equal materials, doc/hard_cases.md)."""
    m = piece.mass[piece.surface()["nodes"]].max()
    return speed * math.sqrt(m / (mat.young * mat.radius))


def _inside(p, q, margin=2e-3):
    """Nodes of p more than `margin` inside q, q taken as the convex solid of
    its surface triangles' planes (the cubes stay nearly convex)."""
    tri = q.pos[q.surface()["triangles"]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = np.einsum("tj,nj->nt", n, p.pos) - np.einsum("tj,tj->t", n, tri[:, 0])[None, :]
    return int((h.max(axis=1) < -margin).sum())


# Radii at which the contact holds each impact within its reach r_a + r_b
# (no node behind the other surface deeper than that: ContactDepthCheck.cpp).
# With r = 2 mm these impacts drove nodes 1.5, 13 and 7 reaches deep; the
# contact kept them on their sides (side memory), but the ledger lost up to
# 23 %: they now stop the step it happens (test_impact_depth.py, below).
@pytest.mark.parametrize("speed, young, radius", [(5.0, 1e7, 5e-3), (25.0, 1e7, 1.2e-2), (50.0, 1e8, 8e-3)])
def test_cubes_hitting_head_on_rebound_on_their_own_sides(speed, young, radius):
    w, a, b, mat = _pair(speed, young, radius=radius)
    assert _stopping(2 * speed, mat, a) < L / 2      # the law can stop them
    w.core.trackEnergy = True
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 1)
    e0 = _mech(w.core.energy)
    p0 = a.momentum + b.momentum
    worst = -np.inf
    for _ in range(int(0.012 / dt)):
        w.core.step(dt, 1)
        worst = max(worst, _mech(w.core.energy) - e0)
    assert a.centroid[0] < b.centroid[0]                    # order kept
    assert a.velocity[0] < 0 < b.velocity[0]                # rebounded
    assert _inside(a, b) == 0 and _inside(b, a) == 0
    assert np.abs(a.momentum + b.momentum - p0).max() < 1e-9 * a.totalMass * speed
    assert worst <= 1e-3 * e0


@pytest.mark.parametrize("speed, young", [(5.0, 1e7), (25.0, 1e7), (50.0, 1e8)])
def test_cubes_hitting_deeper_than_the_reach_stop_the_step_it_happens(speed, young):
    """r = 2 mm: the same impacts drive nodes deeper than the reach."""
    w, a, b, mat = _pair(speed, young)
    dt = 0.8 * w.stableDt()["combined"]
    with pytest.raises(qdem.StabilityError, match=r"piece \d has sunk into piece \d deeper than their contact can "
                                                  r"see: .* beyond the contact reach r_a \+ r_b = 0.002 \+ 0.002 = "
                                                  r"0.004 m, closing at [\d.]+ m/s"):
        w.core.step(dt, int(0.012 / dt))
    assert w.core.iter * dt < 0.006  # during the impact, not after


def test_rotated_cube_hitting_obliquely_stays_on_its_side():
    w, a, b, mat = _pair(25.0, 1e7, ori=((1, 2, 3), 0.5), offset=(0.02, 0.01))
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.012 / dt))
    assert a.centroid[0] < b.centroid[0]
    assert a.velocity[0] < b.velocity[0]
    assert _inside(a, b) == 0


def test_an_impact_the_law_cannot_stop_stops_the_run_naming_speed_and_fix():
    """50 m/s (closing 100 m/s) with E r = 2e4 N/m: stopping distance 4-5 cm
    against a 5 cm half thickness.  Before the fix the cubes passed through.
    Now the node deeper than the reach stops the run before it gets near the
    far side (the pass-through check behind it, PointPolygon.cpp, stays for
    pairs started interpenetrated, which the per-step check lets be)."""
    w, a, b, mat = _pair(50.0, 1e7)
    dt = 0.8 * w.stableDt()["combined"]
    with pytest.raises(qdem.StabilityError, match=r"piece \d has sunk into piece \d deeper than their contact can "
                                                  r"see.* closing at [\d.]+ m/s.*Use a stiffer material.*larger "
                                                  r"radius.*smaller O.dt.*smaller impact speed"):
        w.core.step(dt, int(0.012 / dt))


@pytest.mark.parametrize("speed", [5.0, 25.0, 50.0])
def test_cube_hitting_a_floor_rebounds_above_it(speed):
    w = qdem.World()
    mat = rubber(radius=2e-3, viscosity=100.0, young=1e8)
    p = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(0, 0, L / 2 + 2.5e-3), vel=(0, 0, -speed))
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 0                      # two-sided: side memory holds
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.01 / dt))
    assert p.velocity[2] > 0
    assert p.pos[:, 2].min() > 0


# --- going through obstacles ---------------------------------------------------

def _obstacle(w, kind, sense=0):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId = kind, 7
    if kind == 0:
        o.axis, o.sense = 2, sense
    else:
        o.setVertices((-1, -1, 0), (1, -1, 0), (0, 1.5, 0))
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))


@pytest.mark.parametrize("kind, name", [(0, "wall"), (2, "facet")])
def test_a_node_that_jumps_through_a_thin_obstacle_in_one_step_stops_the_run(kind, name):
    """A two-sided wall or a facet is a surface: a node that moves from one
    side to the other in one step, more than its contact zone r, never touched
    it.  Before, the cube went on through it without a word (a wall pushes
    such a node towards the side it is found on)."""
    w = qdem.World()
    r = 2e-3
    p = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), rubber(radius=r, viscosity=100.0), pos=(0, 0, L / 2 + 1.5 * r))
    _obstacle(w, kind)
    dt = 0.8 * w.stableDt()["combined"]
    p.vel[:] = (0, 0, -3 * r / dt)          # 3 r per step: 1.5 r above to 1.5 r below in step 1, seen in step 2
    with pytest.raises(qdem.StabilityError, match=r"during step 2 node \d+ of piece 0 went through the %s "
                                                  r"\(YADE body 7\) without touching it: it moved 0.006 m in this step"
                                                  r".*Lower O.dt or the speed" % name):
        w.core.step(dt, 3)
    # Slower, the same cube is stopped by the contact and nothing is raised.
    w2 = qdem.World()
    p2 = w2.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), rubber(radius=r, viscosity=100.0), pos=(0, 0, L / 2 + 1.5 * r))
    _obstacle(w2, kind)
    p2.vel[:] = (0, 0, -2.0)
    w2.core.step(dt, int(0.01 / dt))
    assert p2.pos[:, 2].min() > 0 and p2.velocity[2] > 0


def test_a_block_too_heavy_for_its_contact_going_through_a_floor_stops_the_run():
    """The units mistake: a mesh made in millimetres with SI material values
    is a 400 m block on a 1 cm contact zone.  Its contact cannot hold it and
    it sank through the one-sided floor; before, the floor stopped seeing it
    once it was wholly below (the obstacle cull did not match the one-sided
    contact, which pushes however deep) and it fell on for kilometres."""
    w = qdem.World()
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=700, radius=0.01)
    p = w.addPiece(qdem.boxMesh((400, 400, 400), (4, 4, 4)), mat, pos=(0, 0, 300))
    _obstacle(w, 0, sense=1)
    w.core.gravity = (0, 0, -9.81)
    dt = 0.5 * w.stableDt()["combined"]
    with pytest.raises(qdem.StabilityError, match=r"piece 0 went through the one-sided wall \(YADE body 7\): it is "
                                                  r"[\d.]+ m behind the wall's plane, more than the piece's largest "
                                                  r"extent .*stopping distance.*check the mesh's units"):
        w.core.step(dt, 200)
    assert p.pos[:, 2].min() > -1000            # stopped within a few steps of going under


def test_a_piece_started_wholly_behind_a_one_sided_wall_is_refused():
    """Wholly below a one-sided floor: inside the half-space, refused like a
    piece started partly inside (the cull used to leave it unseen)."""
    w = qdem.World()
    w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), rubber(radius=2e-3), pos=(0, 0, -1.0))
    _obstacle(w, 0, sense=1)
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body 7 \(one-sided wall\)"):
        w.core.step(1e-6, 1)
