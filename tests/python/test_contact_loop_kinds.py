"""Node-obstacle and sphere-triangle contacts are rows of the contact-kinds
table (pkg/phases/ContactKind.hpp) beside the piece-piece ones, switched by
QDEM_SETTINGS lines (obstaclesOn: QdemEngine.couple, spheresOn:
QdemEngine.spheres), and the core's obstacle and sphere phases honour them:
switched off, no contact and no force; on again, the contact comes back born
anew (no spring carried over the gap)."""
import numpy as np

import qdem
from qdem import _core

G = 9.80665


def test_sphere_and_obstacle_kinds_are_rows_with_settings_switches():
    kinds = {k["name"]: k for k in _core.contactKinds}
    assert list(kinds)[:4] == ["pointPolygon", "edgeEdge", "wall", "sphere"]
    assert kinds["wall"]["switch"] == "obstaclesOn" and kinds["sphere"]["switch"] == "spheresOn"
    decl = {d["name"]: d for d in _core.settings}
    assert decl["obstaclesOn"]["engineName"] == "couple" and decl["obstaclesOn"]["default"] is True
    assert decl["spheresOn"]["engineName"] == "spheres" and decl["spheresOn"]["default"] is True
    e = qdem.QdemEngine(couple=False, spheres=False)
    assert e.couple is False and e.spheres is False
    assert e.dict()["couple"] is False


def _blockOnFloor(edge=1.0):
    """A cube resting 2 mm into a rigid floor at z = 0, gravity on."""
    mat = qdem.QdemMat()
    w = qdem.World()
    w.addPiece(qdem.boxMesh((edge,) * 3, (3, 3, 3), tetsPerCell=12), mat, pos=(0, 0, edge / 2 + mat.radius - 0.002))
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 7, 2, 1
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))
    w.core.gravity = (0, 0, -G)
    return w, mat


def test_obstacle_contacts_switch_off_and_on_in_the_core():
    w, mat = _blockOnFloor()
    c = w.core
    dt = 0.5 * w.stableDt()["combined"]
    c.step(dt, 1)
    assert c.contactCounts["wall"] > 0
    push = np.array(c.obstacleReactions())[0, 2]
    assert push < 0  # the floor is pushed down
    c.obstaclesOn = False
    v0 = np.array(c.vel).reshape(-1, 3)[:, 2].copy()
    c.step(dt, 1)
    assert c.contactCounts["wall"] == 0
    assert np.all(np.array(c.obstacleReactions()) == 0)
    # no contact force: the block's momentum changes by gravity alone
    m = np.array(c.mass)
    dp = (m * (np.array(c.vel).reshape(-1, 3)[:, 2] - v0)).sum()
    assert abs(dp + m.sum() * G * dt) < 1e-9 * m.sum() * G * dt
    c.obstaclesOn = True
    c.step(dt, 1)
    assert c.contactCounts["wall"] > 0 and np.array(c.obstacleReactions())[0, 2] < 0


def test_sphere_contacts_switch_off_in_the_core():
    w, mat = _blockOnFloor()
    c = w.core
    R = 0.1
    top = 1.0 + mat.radius - 0.002 + mat.radius  # the top face's contact surface
    c.setSpheres(np.array([3], dtype=np.int32), np.array([R]), np.array([1e8]), np.array([0.5]), np.array([0.4]),
                 np.array([0.5]), np.array([2.0]), np.array([0, 1], dtype=np.int32), np.array([0], dtype=np.int32))
    c.setSphereStates(np.array([[0.0, 0.0, top + R - 0.01]]), np.zeros((1, 3)), np.zeros((1, 3)))
    dt = 0.5 * w.stableDt()["combined"]
    c.step(dt, 1)
    assert c.contactCounts["sphere"] > 0
    assert np.array(c.sphereForceTorque())[0, 2] > 0  # the block pushes the sphere up
    c.spheresOn = False
    c.step(dt, 1)
    assert c.contactCounts["sphere"] == 0
    assert np.all(np.array(c.sphereForceTorque()) == 0)
