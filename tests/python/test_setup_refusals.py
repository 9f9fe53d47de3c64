"""Set-up mistakes are refused with a message naming the fix (issue 12, item 4):
a mesh of parts that share no node (its parts would pass through each other)
and a piece started inside a YADE wall, box or facet (it would be launched,
or held across a two-sided wall).  Each case is also run the way that must
still work: each part its own piece, a piece resting on the obstacle, a
restarted run whose contacts are deep."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber

L, R = 0.1, 0.005


def _cube(cells=3):
    return qdem.boxMesh((L, L, L), (cells,) * 3)


# --- disconnected meshes ------------------------------------------------------

def _twoBlocks():
    m = _cube()
    return np.vstack([m.nodes, m.nodes + (0.3, 0, 0)]), np.vstack([m.tets, m.tets + m.nNodes])


def _cutBlock():
    """A 4x2x2-cell bar cut across its middle by duplicating the nodes of the
    plane x = 0 for the tets on its +x side: geometrically one block, two parts."""
    m = qdem.boxMesh((0.2, 0.1, 0.1), (4, 2, 2))
    nodes, tets = m.nodes.copy(), m.tets.copy()
    onCut = np.where(np.isclose(nodes[:, 0], 0.0))[0]
    twin = {int(n): len(nodes) + k for k, n in enumerate(onCut)}
    nodes = np.vstack([nodes, nodes[onCut]])
    right = nodes[tets].mean(axis=1)[:, 0] > 0
    tets[right] = np.vectorize(lambda n: twin.get(int(n), int(n)))(tets[right])
    return nodes, tets


@pytest.mark.parametrize("make, sizes", [(_twoBlocks, "162 tets/64 nodes, 162 tets/64 nodes"),
                                         (_cutBlock, "48 tets/27 nodes, 48 tets/27 nodes")])
def test_a_mesh_of_disconnected_parts_is_refused_naming_the_parts_and_the_fix(make, sizes):
    nodes, tets = make()
    w = qdem.World()
    with pytest.raises(ValueError, match=r"mesh: 2 parts that share no node \(sizes: %s\).*"
                                         r"qdem.splitMesh\(mesh\) and add each part with qdem.addPiece" % sizes):
        w.addPiece((nodes, tets), rubber())
    assert w.core.nPieces == 0
    parts = qdem.splitMesh((nodes, tets))
    assert [p.nTets for p in parts] == [len(tets) // 2] * 2
    assert sum(p.volumes().sum() for p in parts) == pytest.approx(qdem._core.tetVolumes(nodes, tets).sum())
    for p in parts:
        w.addPiece(p, rubber())
    assert w.core.nPieces == 2


def test_the_halves_of_a_cut_block_added_as_pieces_do_not_pass_through_each_other():
    """The issue's case: the two halves of a cut bar pushed together at 1 m/s.
    As two pieces they touch and stay on their own sides."""
    w = qdem.World()
    a, b = (w.addPiece(p, rubber(radius=2e-3, viscosity=50.0)) for p in qdem.splitMesh(_cutBlock()))
    if a.centroid[0] > b.centroid[0]:
        a, b = b, a
    a.pos[:, 0] -= 0.004                      # just apart: the reach of two 2 mm radii
    a.vel[:, 0], b.vel[:, 0] = 1.0, -1.0
    dt = 0.8 * w.stableDt()["combined"]
    touching = 0                                             # steps with point-polygon contacts between them
    for _ in range(int(0.02 / dt)):
        w.core.step(dt, 1)
        touching += w.core.contactCounts["pointPolygon"] > 0
    assert touching * dt > 2e-3                              # they touched (for 4.2 ms)
    assert a.pos[:, 0].max() < b.pos[:, 0].min() + 2e-3      # no node of one past the other's face
    assert a.velocity[0] < 0 < b.velocity[0]             # they bounced apart


# --- pieces started inside obstacles (core) ---------------------------------

def _set(w, obstacle, state):
    w.core.setObstacles([obstacle])
    w.core.setObstacleStates(np.array([state], dtype=float))


def _wall(sense, bodyId=3):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, bodyId, 2, sense
    return o, [0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]


def _box(bodyId=4):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.halfExtents = 1, bodyId, (1.0, 1.0, 0.1)
    return o, [0, 0, -0.1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]     # top face at z = 0


def _facet(bodyId=5):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId = 2, bodyId
    o.setVertices((-1, -1, 0), (1, -1, 0), (0, 1.5, 0))
    return o, [0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]


@pytest.mark.parametrize("make, kind", [(lambda: _wall(1), "one-sided wall"), (lambda: _wall(0), "two-sided wall"),
                                        (_box, "box"), (_facet, "facet")])
def test_a_piece_started_inside_an_obstacle_is_refused_naming_depth_and_fix(make, kind):
    """The cube's bottom 2 cm start below the obstacle's surface at z = 0."""
    w = qdem.World()
    w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 - 0.02))
    o, state = make()
    _set(w, o, state)
    before = w.core.pos.copy()
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body %d \(%s\): 16 of its 56 surface "
                                         r"nodes are past its surface, the deepest by 0.02 m.*start it at least "
                                         r"0.025 m higher" % (o.bodyId, kind)):
        w.core.step(1e-6, 1)
    assert np.array_equal(w.core.pos, before)            # refused before anything moved
    # A script that catches the refusal and runs again (moved not far enough,
    # or not at all) is refused again: the check was marked done and the
    # retry launched the piece.
    w.core.pos[:, 2] += 0.01
    before = w.core.pos.copy()
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body %d.*the deepest by 0.01 m"
                                         % o.bodyId):
        w.core.step(1e-6, 1)
    assert np.array_equal(w.core.pos, before)


@pytest.mark.parametrize("make", [lambda: _wall(1), lambda: _wall(0), _box, _facet])
def test_a_piece_resting_on_an_obstacle_is_not_refused(make):
    """Placed with the overlap it has at rest (node centres outside): accepted,
    and the cube stays on the obstacle instead of being thrown up."""
    w = qdem.World()
    p = w.addPiece(_cube(), rubber(radius=R, viscosity=50.0), pos=(0, 0, L / 2 + R - 5e-6))
    _set(w, *make())
    w.core.gravity = (0, 0, -9.81)
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.05 / dt))
    assert np.abs(p.velocity).max() < 0.05                  # not launched (a launch is metres per second)
    assert p.pos[:, 2].min() > 0                               # and on the obstacle's top side


def test_a_restarted_run_with_deep_contacts_is_not_refused(tmp_path):
    """A cube saved mid-impact with a node past the floor: loaded into a fresh
    world with the same floor, it goes on (only set-ups are checked)."""
    def scene():
        w = qdem.World()
        p = w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 + R), vel=(0, 0, -20.0))
        _set(w, *_wall(1))
        return w, p
    w, p = scene()
    dt = 0.8 * w.stableDt()["combined"]
    for _ in range(2000):                                      # until a node centre is past the floor
        w.core.step(dt, 1)
        if p.pos[:, 2].min() < -1e-4:
            break
    assert p.pos[:, 2].min() < -1e-4
    path = str(tmp_path / "deep.qdem")
    qdem.saveState(path, world=w)
    w.core.step(dt, 10)
    w2, p2 = scene()
    qdem.loadState(path, world=w2)
    w2.core.step(dt, 10)
    assert np.array_equal(w2.core.pos, w.core.pos)


def test_a_new_piece_or_a_new_obstacle_list_is_checked_again():
    w = qdem.World()
    w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, 0.5))
    _set(w, *_wall(1))
    w.core.step(1e-6, 1)
    w.addPiece(_cube(), rubber(radius=R), pos=(0.5, 0, 0.0))          # half below the floor
    with pytest.raises(ValueError, match=r"piece 1 starts inside .* deepest by 0.05 m"):
        w.core.step(1e-6, 1)
    w = qdem.World()
    w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, 0.0))
    w.core.step(1e-6, 1)                                               # no obstacle yet
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body 4 \(box\)"):
        _set(w, *_box())
        w.core.step(1e-6, 1)


def test_an_obstacle_added_elsewhere_during_an_impact_leaves_the_piece_alone():
    """A tester's case: a cube hitting a floor at 3 m/s overlaps it by 1.5 r, an
    ordinary impact. A facet added 5 m away at that moment stopped the run
    ("starts inside obstacle body 0"): every new obstacle list re-checked every
    piece against every obstacle. Only the new obstacle is checked now, and the
    run is the one without it, to the bit."""
    def run(addFacet):
        w = qdem.World()
        mat = qdem.QdemMat(young=2e5, poisson=0.3, density=1000, viscosity=20, radius=R, restitution=0.5)
        p = w.addPiece(_cube(), mat, pos=(0, 0, 0.06), vel=(0, 0, -3.0))
        w.core.gravity = (0, 0, -9.81)
        floor = _wall(1)
        _set(w, *floor)
        dt = 0.5 * w.core.stableDt()["combined"]
        while R - p.pos[:, 2].min() < 1.5 * R:
            w.core.step(dt, 1)
        if addFacet:
            far = qdem._core.Obstacle()
            far.kind, far.bodyId = 2, 7
            far.setVertices(np.array([5.0, 5, 0.5]), np.array([6.0, 5, 0.5]), np.array([5.0, 6, 0.5]))
            w.core.setObstacles([floor[0], far])
            w.core.setObstacleStates(np.array([floor[1], floor[1]], dtype=float))
        w.core.step(dt, 2000)
        return p.pos.copy(), p.velocity
    (x0, v0), (x1, v1) = run(False), run(True)
    assert v0[2] > 0.3                                   # it bounced
    assert np.array_equal(x0, x1) and np.array_equal(v0, v1)


def test_a_new_obstacle_inside_a_running_piece_is_still_refused():
    """The check of a new obstacle is kept: a box put across the top face of a
    cube resting on a floor is refused, naming the box."""
    w = qdem.World()
    w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 + R))
    floor = _wall(1)
    _set(w, *floor)
    w.core.step(1e-6, 5)
    box = qdem._core.Obstacle()
    box.kind, box.bodyId, box.halfExtents = 1, 9, (0.02, 0.02, 0.02)
    w.core.setObstacles([floor[0], box])
    w.core.setObstacleStates(np.array([floor[1], [0, 0, L + R] + floor[1][3:]], dtype=float))
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body 9 \(box\)"):
        w.core.step(1e-6, 1)


def _far(bodyId, x):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId = 2, bodyId
    o.setVertices(np.array([x, 5, 0.5]), np.array([x + 1, 5, 0.5]), np.array([x, 6, 0.5]))
    return o


def _setAll(w, obstacles, rows=None):
    w.core.setObstacles(obstacles)
    rest = _wall(1)[1]
    w.core.setObstacleStates(np.array(rows if rows is not None else [rest] * len(obstacles), dtype=float))


def _impactWorld():
    """A cube falling at 3 m/s onto a floor, no floor yet."""
    w = qdem.World()
    mat = qdem.QdemMat(young=2e5, poisson=0.3, density=1000, viscosity=20, radius=R, restitution=0.5)
    p = w.addPiece(_cube(), mat, pos=(0, 0, 0.06), vel=(0, 0, -3.0))
    w.core.gravity = (0, 0, -9.81)
    return w, p, 0.5 * w.core.stableDt()["combined"]


def _intoImpact(w, p, dt):
    while R - p.pos[:, 2].min() < 1.5 * R:
        w.core.step(dt, 1)


def test_a_loaded_state_knows_its_obstacles_whatever_list_was_in_force_before():
    """A review's cases. (a) Saved mid-impact with [far facet, floor]; the
    list replaced by two facets; the state loaded and the saved list set
    again: the saved run's floor was taken as new and refused. (b) Saved
    before the floor existed, the floor added, the state loaded, an impact,
    then a far facet added: the floor, known since the load, was checked
    again mid-impact and refused.  Each run goes on exactly as the same run
    without the detour (same trajectory to the bit), the floor pushing the
    cube back."""
    w, p, dt = _impactWorld()
    saved_list = [_far(7, 5.0), _wall(1)[0]]
    _setAll(w, saved_list)
    _intoImpact(w, p, dt)
    saved = w.core.saveState()
    vz = p.velocity[2]
    w.core.step(dt, 5)                                            # the run without the detour
    ref = w.core.pos.copy()
    assert p.velocity[2] > vz                                   # the floor pushes back
    w.core.loadState(saved)
    _setAll(w, [_far(7, 5.0), _far(9, 20.0)])
    w.core.step(dt, 1)
    w.core.loadState(saved)
    _setAll(w, saved_list)
    w.core.step(dt, 5)                                            # (a): no refusal
    assert np.array_equal(w.core.pos, ref)

    def impactAfterLoad(detour):
        w, p, dt = _impactWorld()
        _setAll(w, [_far(7, 5.0)])
        w.core.step(dt, 1)
        saved = w.core.saveState()                                # in the air, no floor
        _setAll(w, [_far(7, 5.0), _wall(9)[0]])
        if detour:
            w.core.step(dt, 1)
            w.core.loadState(saved)
        _intoImpact(w, p, dt)
        vz = p.velocity[2]
        _setAll(w, [_far(7, 5.0), _wall(9)[0], _far(11, 40.0)])
        w.core.step(dt, 5)                                        # (b): no refusal
        assert p.velocity[2] > vz                               # the floor pushes back
        return w.core.pos.copy()

    assert np.array_equal(impactAfterLoad(True), impactAfterLoad(False))


@pytest.mark.parametrize("twoChanges", [False, True])
def test_an_obstacle_added_by_one_of_two_list_changes_before_a_step_is_still_checked(twoChanges):
    """A review's case: a box put into a resting cube, then (before the step)
    a far facet added as well: the second change forgot the box's check."""
    w = qdem.World()
    w.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 + R))
    floor, rest = _wall(1)
    _setAll(w, [floor])
    w.core.step(1e-6, 5)
    box = qdem._core.Obstacle()
    box.kind, box.bodyId, box.halfExtents = 1, 9, (0.02, 0.02, 0.02)
    boxRow = [0, 0, L + R] + rest[3:]
    _setAll(w, [floor, box], [rest, boxRow])
    if twoChanges:
        _setAll(w, [floor, box, _far(11, 40.0)], [rest, boxRow, rest])
    for _ in range(2):                                            # refused again if run again unchanged
        with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body 9 \(box\)"):
            w.core.step(1e-6, 1)


def test_rewinding_with_load_tmp_after_erasing_an_obstacle_warns_of_nothing(scene):
    """O.loadTmp into a fresh world, after the scene had lost a facet: the
    obstacles the saved run had are not new, and a cube touching its floor is
    not "placed pressed into" it (a false RuntimeWarning before)."""
    import warnings
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=R, frictionWall=0.4)
    qdem.addPiece(_cube(), mat, pos=(0, 0, 0.1), vel=(0.3, 0, 0), angVel=(1, 2, 0))
    O.bodies.append(utils.wall(0, axis=2))
    f = O.bodies.append(utils.facet([(-1, -1, 0.0), (1, -1, 0.0), (0, 1, 0.5)]))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    O.run(800, True)
    O.saveTmp("rewind")
    O.run(600, True)
    ref = qdem.defaultWorld().pieces[0].pos.copy()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        O.loadTmp("rewind")
        O.bodies.erase(f)
        O.run(300, True)
        O.loadTmp("rewind")
        O.run(600, True)
    assert np.array_equal(qdem.defaultWorld().pieces[0].pos, ref)


# --- through QdemEngine in YADE ---------------------------------------------

@pytest.mark.parametrize("what", ["floor", "wall", "box", "facet"])
def test_yade_obstacles_overlapping_a_new_piece_stop_the_run_with_the_fix(scene, what):
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    qdem.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 - 0.03))
    body = {"floor": lambda: utils.wall(0, axis=2, sense=1), "wall": lambda: utils.wall(0, axis=2),
            "box": lambda: utils.box((0, 0, -0.1), (1, 1, 0.1), fixed=True),
            "facet": lambda: utils.facet([(-1, -1, 0), (1, -1, 0), (0, 1.5, 0)], fixed=True)}[what]()
    bid = O.bodies.append(body)
    O.engines = [ForceResetter(), qdem.QdemEngine(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableDt()["combined"]
    with pytest.raises(ValueError, match=r"piece 0 starts inside obstacle body %d .*deepest by 0.03 m.*"
                                         r"start it at least 0.035 m higher" % bid):
        O.engines[1].stepOnce()


# --- pieces started inside other pieces (core) ------------------------------

def _twoCubes(overlap, size=0.4, cells=4, r=0.01, ori=None):
    w = qdem.World()
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000, viscosity=700, radius=r)
    a = w.addPiece(qdem.boxMesh((size,) * 3, (cells,) * 3), mat, pos=(0, 0, 0))
    b = w.addPiece(qdem.boxMesh((size,) * 3, (cells,) * 3), mat, pos=(size - overlap, 0.0, 0), ori=ori)
    return w, a, b


@pytest.mark.parametrize("overlap", [0.1, 0.3])
def test_a_piece_started_inside_another_beyond_the_contacts_sight_is_refused(overlap):
    """Two 0.4 m cubes of 0.1 m cells placed 10 or 30 cm into each other:
    their faces meet along planes of nodes, no node centre lies behind a face
    within the contact's reach, so nothing pushes them apart.  Before, they
    stayed interpenetrated for good, without a word."""
    w, a, b = _twoCubes(overlap)
    before = w.core.pos.copy()
    with pytest.raises(ValueError, match=r"piece [01] starts inside piece [01], deeper than the contact can see: "
                                         r"node \d+ of piece [01] is 0.1 m inside.*Place them apart \(by at least "
                                         r"0.12 m"):
        w.core.step(1e-5, 1)
    assert np.array_equal(w.core.pos, before)
    with pytest.raises(ValueError, match=r"starts inside piece [01], deeper than the contact can see"):
        w.core.step(1e-5, 1)  # caught and run again unchanged: refused again (it ran on)
    assert np.array_equal(w.core.pos, before)


def test_pieces_started_interpenetrated_within_the_contacts_sight_separate():
    """2 cm into each other: the contact sees the nodes inside and pushes the
    cubes apart (a packing generated with overlaps relaxes; the energy they
    leave with is the overlap's: test_hard_cases.py checks none is gained)."""
    w, a, b = _twoCubes(0.02)
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 3000)
    assert b.pos[:, 0].min() > a.pos[:, 0].max()


def test_a_piece_started_wholly_inside_another_is_refused():
    w = qdem.World()
    mat = rubber(radius=R)
    w.addPiece(qdem.boxMesh((0.6, 0.6, 0.6), (3, 3, 3)), mat)
    w.addPiece(_cube(), mat, pos=(0.02, 0.01, 0.0))
    with pytest.raises(ValueError, match=r"piece 1 starts inside piece 0, deeper than the contact can see"):
        w.core.step(1e-6, 1)


@pytest.mark.parametrize("gap", [0.0, 0.01, 0.03])
def test_pieces_touching_each_other_are_not_refused(gap):
    """Faces that coincide (node centres on the other's surface), contact
    zones that overlap by half the reach (0.02 m), or apart: accepted.  (With
    their zones overlapping they are pushed apart: the contact law, not a
    set-up mistake.)"""
    w, a, b = _twoCubes(-gap)
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 200)
    assert a.velocity[0] <= 1e-12 and b.velocity[0] >= -1e-12  # apart or at rest, never drawn in


def test_a_piece_added_into_a_running_scene_is_checked_and_a_loaded_deep_contact_is_not(tmp_path):
    w = qdem.World()
    mat = rubber(radius=R, viscosity=50.0)
    a = w.addPiece(_cube(), mat, pos=(0, 0, 0))
    w.addPiece(_cube(), mat, pos=(L + 0.01, 0, 0), vel=(-30.0, 0, 0))     # a hard hit: contacts go deep
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, 400)
    path = str(tmp_path / "hit.qdem")
    qdem.saveState(path, world=w)
    w2 = qdem.World()
    w2.addPiece(_cube(), mat, pos=(0, 0, 0))
    w2.addPiece(_cube(), mat, pos=(L + 0.01, 0, 0), vel=(-30.0, 0, 0))
    qdem.loadState(path, world=w2)
    w2.core.step(dt, 5)                                                    # a restart: goes on
    w2.addPiece(qdem.boxMesh((0.03, 0.03, 0.03), (2, 2, 2)), mat, pos=a.centroid)  # wholly inside piece 0
    with pytest.raises(ValueError, match=r"piece 2 starts inside piece 0"):
        w2.core.step(dt, 1)


# --- engines whose place in O.engines matters ------------------------------------

def _fallingPieceAndSphere(O, order):
    from yade import (Bo1_Sphere_Aabb, ForceResetter, GlobalStiffnessTimeStepper, InsertionSortCollider,
                      InteractionLoop, Ig2_Sphere_Sphere_ScGeom, Ip2_FrictMat_FrictMat_FrictPhys,
                      Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator, utils)
    qdem.addPiece(_cube(2), rubber(radius=R), pos=(0, 0, 1.0))
    O.bodies.append(utils.sphere((1.0, 0, 1.0), 0.05))
    stepper = GlobalStiffnessTimeStepper(timeStepUpdateInterval=1, defaultDt=1e-5)
    engine = qdem.QdemEngine()
    middle = [engine, stepper] if order == "qdem first" else [stepper, engine]
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                 [Law2_ScGeom_FrictPhys_CundallStrack()])] + middle + [
                     NewtonIntegrator(gravity=(0, 0, -9.81), damping=0)]
    O.dt = 1e-5


def test_a_time_stepper_between_qdem_engine_and_newton_is_refused(scene):
    """GlobalStiffnessTimeStepper where YADE's scripts put it, right before
    NewtonIntegrator, with QdemEngine inserted after InteractionLoop: it set
    O.dt after QDEM had stepped with the old one, and a falling piece ended
    2.6 mm behind a sphere falling beside it (QDEM's clock 2.3e-4 s behind
    O.time after one change).  Before QdemEngine, both fall alike."""
    O = scene
    _fallingPieceAndSphere(O, "qdem first")
    with pytest.raises(Exception, match=r"GlobalStiffnessTimeStepper at O.engines\[4\] sets O.dt after "
                                        r"QdemEngine \(O.engines\[3\]\).*Put it before QdemEngine"):
        O.run(5, True)
    O.reset()
    _fallingPieceAndSphere(O, "stepper first")
    O.run(200, True)
    w = qdem.defaultWorld()
    assert w.core.time == pytest.approx(O.time, rel=1e-12)
    z = w.pieces[0].centroid[2]
    assert z - 1.0 == pytest.approx(O.bodies[0].state.pos[2] - 1.0, rel=1e-9)


def _servoedPlaten(O, servoFirst):
    from yade import ForceResetter, NewtonIntegrator, ServoPIDController, utils
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=50, radius=0.004, restitution=0.3,
                       frictionWall=0.0)
    qdem.addPiece(_cube(3), mat, pos=(0, 0, L / 2 + 0.004))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    top = O.bodies.append(utils.box((0, 0, L + 0.008 + 0.011), (0.1, 0.1, 0.01), fixed=True))
    servo = ServoPIDController(ids=[top], axis=(0, 0, 1), target=20.0, kP=2e-4, kI=0, kD=0, maxVelocity=0.02,
                               iterPeriod=1)
    engine = qdem.QdemEngine()
    middle = [servo, engine] if servoFirst else [engine, servo]
    O.engines = [ForceResetter()] + middle + [NewtonIntegrator(gravity=(0, 0, 0))]
    O.dt = 0.5 * engine.stableTimeStep()
    return top


def test_a_servo_controller_reads_qdem_reactions_after_qdem_engine(scene):
    """ServoPIDController drives a platen to a force it reads from O.forces.
    Before QdemEngine it read none of QDEM's reactions and pressed on for
    ever (134 N against a 20 N target): refused, naming the order.  After
    it, YADE 2023.02a stopped on an unsynchronised ForceContainer unless
    synchronised; QdemEngine does so, and the platen settles on the target."""
    O = scene
    _servoedPlaten(O, servoFirst=True)
    with pytest.raises(Exception, match=r"ServoPIDController at O.engines\[1\] reads the force on its bodies "
                                        r"before QdemEngine \(O.engines\[2\]\).*Put it after QdemEngine"):
        O.run(5, True)
    O.reset()
    top = _servoedPlaten(O, servoFirst=False)
    O.run(int(1.2 / O.dt), True)
    assert O.forces.f(top, sync=True)[2] == pytest.approx(20.0, rel=0.02)


# --- bodies pieces cannot collide with; a stopped engine --------------------

def _polyhedronSlab(O):
    import yade
    from yade import polyhedra_utils
    b = polyhedra_utils.polyhedra(yade.PolyhedraMat(young=1e8), size=(1, 1, 0.1))   # top at z = 0.05
    b.state.pos = (0, 0, 0)
    b.dynamic = False
    return O.bodies.append(b)


def _gridNode(O):
    import yade
    from yade import gridpfacet
    O.materials.append(yade.CohFrictMat(young=1e8, label="gm"))
    return O.bodies.append(gridpfacet.gridNode((0, 0, 0), 0.05, wire=False, fixed=True, material="gm"))


@pytest.mark.parametrize("make, shapes", [(_polyhedronSlab, "Polyhedra"),
                                          (_gridNode, "GridNode")])
def test_a_body_pieces_cannot_collide_with_stops_the_run_naming_it_and_the_fix(scene, make, shapes):
    """A tester's case: a block dropped on a fixed Polyhedra slab (or a grid
    beam) fell straight through it, unwarned: QDEM reads Wall, Box, Facet and
    Sphere bodies only.  Such a body is refused at the first step; named in
    ignoreShapes, it is left alone (the script says no piece reaches it)."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    qdem.addPiece(_cube(), rubber(radius=R), pos=(0, 0, 0.3))
    bid = make(O)
    qe = qdem.QdemEngine()
    O.engines = [ForceResetter(), qe, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * qe.stableTimeStep()
    with pytest.raises(qdem.SetupError, match=r"bod(y|ies) .*%d.* of shape %s, which QDEM pieces do not collide "
                                              r"with: a piece would pass through .*facets .*"
                                              r"QdemEngine\(ignoreShapes=\[" % (bid, shapes)):
        O.run(5, True)
    qe.ignoreShapes = shapes.split(" and ")
    O.run(5, True)
    assert qe.world.core.iter == O.iter
    with pytest.raises(ValueError, match=r"ignoreShapes=.*a list of YADE shape class names"):
        qe.ignoreShapes = "Polyhedra"


def test_an_erased_refused_body_is_refused_no_more_and_couple_toggled_scans_again(scene):
    """A review's cases: a Polyhedra slab refused, then erased (O.bodies keeps
    its length): the same refusal came again. And couple=False then True
    never scanned O.bodies again: pieces fell through the floor."""
    from yade import ForceResetter, NewtonIntegrator, utils
    O = scene
    p = qdem.addPiece(_cube(), rubber(radius=R), pos=(0, 0, L / 2 + R + 0.01))
    slab = _polyhedronSlab(O)
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    qe = qdem.QdemEngine()
    O.engines = [ForceResetter(), qe, NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * qe.stableTimeStep()
    with pytest.raises(qdem.SetupError, match="body %d is of shape Polyhedra" % slab):
        O.run(1, True)
    O.bodies.erase(slab)
    O.run(10, True)
    qe.couple = False
    O.run(10, True)
    assert qe.world.core.nObstacles == 0
    qe.couple = True
    O.run(1, True)
    assert qe.world.core.nObstacles == 1                          # the floor again
    p.vel[:] = (0, 0, -1.0)
    O.run(int(0.1 / O.dt), True)
    assert p.pos[:, 2].min() > 0                                  # on the floor, not through it


def test_a_saved_edge_feature_angle_above_pi_loads_as_the_angle_it_acted_as():
    """A review's case: scenes saved with edgeFeatureAngle above pi (accepted
    before: "above pi: none", the help said) must still load: the angle went
    through a cosine, so it acted as acos(cos(v))."""
    from qdem.yade import lifecycle
    with pytest.warns(RuntimeWarning, match=r"edgeFeatureAngle = 4, above pi.*acos\(cos\(4\)\) = 2.28319"):
        s = lifecycle.savedSettings({"edgeFeatureAngle": 4.0, "verletSkin": 0.5})
    assert s == {"edgeFeatureAngle": pytest.approx(math.acos(math.cos(4.0))), "verletSkin": 0.5}
    qdem.QdemEngine(**s)                                          # accepted


def test_a_qdem_engine_stopped_for_some_steps_warns_and_its_clock_follows_yades_again(scene, tmp_path):
    """A tester's case: 100 steps with QdemEngine.dead = True left QDEM's clock
    100 steps behind O.iter for good, frames named by QDEM's step, unwarned.
    Now: a RuntimeWarning naming the gap, and the clocks equal again."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    qdem.addPiece(_cube(2), rubber(radius=R), pos=(0, 0, 0.5))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"),
                 qdem.VtkRecorder(fileBase=str(tmp_path / "f-"), iterPeriod=100), NewtonIntegrator(gravity=(0, 0, -9.81))]
    qe = O.engines[1]
    O.dt = 0.5 * qe.stableTimeStep()
    O.run(100, True)
    qe.dead = True
    O.run(100, True)
    qe.dead = False
    with pytest.warns(RuntimeWarning, match=r"did not run in the 100 steps before O.iter = 200 .*dead=True.*"
                                            r"stood still.*jumps from step 100"):
        O.run(200, True)
    assert (qe.world.core.iter, qe.world.core.time) == (O.iter, pytest.approx(O.time, rel=1e-12))
    assert sorted(p.name for p in tmp_path.glob("*.vtu"))[-1] == "f-000400.vtu"
    # QDEM taken out of O.engines for 50 steps, then a new engine on the same world
    O.engines = [ForceResetter(), NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.run(50, True)
    qe2 = qdem.QdemEngine()
    O.engines = [ForceResetter(), qe2, NewtonIntegrator(gravity=(0, 0, -9.81))]
    with pytest.warns(RuntimeWarning, match=r"did not run in the 50 steps before O.iter = 450"):
        O.run(10, True)
    assert (qe2.world.core.iter, qe2.world.core.time) == (O.iter, pytest.approx(O.time, rel=1e-12))


def _defaultDtNotes(O, steps=20):
    import warnings
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        O.run(steps, True)
    return [str(w.message) for w in caught if "YADE's default" in str(w.message)]


@pytest.mark.parametrize("dt", ["untouched", "set smaller", "set by a time stepper", "near the stable step"])
def test_yades_default_dt_far_below_the_stable_step_is_noted_once(scene, dt):
    """O.dt left at YADE's default 1e-8 s while QDEM's stable step is 1e-4 s
    ran 10^4 times more steps than needed, and nothing said so: a one-time
    RuntimeWarning names the stable step and the line to write.  An O.dt set
    smaller on purpose, one a time stepper sets, and the default where it is
    within 100 times the stable step (a stiff, fine piece) are not noted."""
    from yade import ForceResetter, GlobalStiffnessTimeStepper, NewtonIntegrator
    O = scene
    if dt == "near the stable step":              # steel, 2 mm cells: a stable step ~1e-7 s
        mat = qdem.QdemMat(young=2e11, poisson=0.3, density=7800, viscosity=0.0, radius=2e-4)
        qdem.addPiece(qdem.boxMesh((0.01, 0.01, 0.01), (5, 5, 5)), mat, pos=(0, 0, 0.5))
    else:
        qdem.addPiece(_cube(), rubber(radius=R), pos=(0, 0, 0.5))
    qe = qdem.QdemEngine(label="qe")
    stepper = [GlobalStiffnessTimeStepper(defaultDt=1e-8, timeStepUpdateInterval=10 ** 9)] \
        if dt == "set by a time stepper" else []
    O.engines = [ForceResetter()] + stepper + [qe, NewtonIntegrator(gravity=(0, 0, -9.81))]
    assert O.dt == 1e-8                                           # YADE's default
    stable = qe.stableTimeStep()
    if dt == "set smaller":
        O.dt = 5e-9
    notes = _defaultDtNotes(O)
    assert O.dt in (1e-8, 5e-9)
    if dt != "untouched":
        assert notes == [], notes
        assert (stable < 100 * O.dt) == (dt == "near the stable step")
        return
    assert stable > 1e4 * O.dt
    assert len(notes) == 1, notes
    assert ("O.dt = 1e-08 s is YADE's default, %.3g times below QDEM's stable time step %.6g s "
            "(QdemEngine.stableTimeStep())" % (stable / 1e-8, stable)) in notes[0], notes[0]
    assert "Set O.dt = 0.8 * qe.stableTimeStep() (qe: this QdemEngine (label 'qe'))" in notes[0], notes[0]
    assert _defaultDtNotes(O) == []                               # once
    O.dt = 0.8 * qe.stableTimeStep()
    assert _defaultDtNotes(O) == []


def test_yades_default_dt_is_weighed_once_a_piece_is_there(scene):
    """Before any piece the stable step is inf (nothing limits it): no note
    saying O.dt is 'inf times' too small; the piece added later is noted."""
    from yade import ForceResetter, NewtonIntegrator
    O = scene
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe"), NewtonIntegrator(gravity=(0, 0, -9.81))]
    assert _defaultDtNotes(O, 5) == []
    qdem.addPiece(_cube(), rubber(radius=R), pos=(0, 0, 0.5))
    notes = _defaultDtNotes(O, 5)
    assert len(notes) == 1 and "1.4e+04 times below" in notes[0], notes
