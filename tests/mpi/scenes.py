"""Scenes the MPI tests run serially and on P ranks (tests/mpi/README.md)."""
import numpy as np

import qdem
from qdem import _core


def floor(z=0.0, young=1e8, friction=0.5):
    """A floor wall at height z (YADE's Wall along axis 2, seen from above)."""
    o = _core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    o.young, o.friction = young, friction
    return o


def contactFree(viscosity=0.0, energy=True):
    """Several pieces of other sizes, shapes and orientations, falling under
    gravity on a floor; they never touch each other (contacts between pieces
    are off): the element, obstacle and integration phases only."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=viscosity, radius=0.004,
                       restitution=0.5, frictionWall=0.4)
    stiff = qdem.QdemMat(young=8e6, poisson=0.25, density=1500.0, viscosity=viscosity, radius=0.004,
                         restitution=0.3, frictionWall=0.6)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.2, 0.1, 0.08), (8, 4, 3)), mat, pos=(0, 0, 0.045), vel=(0.3, 0, 0))
    w.addPiece(qdem.boxMesh((0.06, 0.06, 0.06), (3, 3, 3)), stiff, pos=(0.3, 0.05, 0.1),
               ori=((1, 1, 0), 0.6), angVel=(0, 0, 3.0))
    w.addPiece(qdem.boxMesh((0.1, 0.05, 0.05), (5, 3, 3)), mat, pos=(-0.25, 0.1, 0.2), ori=((0, 1, 1), 1.1),
               vel=(0, -0.2, -0.5))
    w.addPiece(qdem.boxMesh((0.3, 0.02, 0.02), (12, 1, 1)), stiff, pos=(0.0, -0.25, 0.15))
    c = w.core
    c.pointPolygonOn = False
    c.edgeEdgeOn = False
    c.gravity = (0, 0, -9.81)
    c.trackEnergy = energy
    c.setObstacles([floor()])
    return w


def positions(w):
    return np.array(w.core.pos, copy=True), np.array(w.core.vel, copy=True)


def withContacts(friction=0.5):
    """A slab on a floor with three cubes resting on it, one sliding across
    (the split cuts the slab: contacts cross rank boundaries), and a rotated
    cube falling on its edge: point-polygon and edge-edge contacts."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004,
                       restitution=0.5, frictionWall=friction, frictionPiece=friction)
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.4, 0.2, 0.04), (10, 5, 1)), mat, pos=(0, 0, 0.024))
    top = 0.044 + 2 * 0.004
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(-0.12, 0.0, top + 0.025 - 0.0005),
               vel=(1.0, 0, 0))
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.1, 0.05, top + 0.025 - 0.0005))
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.1, -0.05, top + 0.045),
               ori=((1, 0, 0), 0.785398), vel=(0, 0, -0.5))
    # Crossed edges: a cube on its edge along x, another on its edge along y
    # falling onto it (edge-edge contact).
    h = 0.025 * 2 ** 0.5
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.32, 0.0, h + 0.0035),
               ori=((1, 0, 0), 0.785398))
    w.addPiece(qdem.boxMesh((0.05, 0.05, 0.05), (2, 2, 2)), mat, pos=(0.32, 0.0, 3 * h + 0.0035 + 0.009),
               ori=((0, 1, 0), 0.785398), vel=(0, 0, -0.8))
    c = w.core
    c.gravity = (0, 0, -9.81)
    c.trackEnergy = True
    c.setObstacles([floor(friction=friction)])
    return w


def frictionHold(friction=0.5, tilt=0.3):
    """A cube resting on a fixed slab under gravity tilted by tan = `tilt`
    below the friction coefficient: static friction must hold it (creep only
    by the tangential spring).  On several ranks the split cuts the slab under
    the cube."""
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004,
                       restitution=0.5, frictionWall=friction, frictionPiece=friction)
    w = qdem.World()
    slab = w.addPiece(qdem.boxMesh((0.3, 0.2, 0.04), (9, 6, 1)), mat, pos=(0, 0, 0.024))
    slab.blocked[:] = 7
    cube = w.addPiece(qdem.boxMesh((0.06, 0.06, 0.06), (3, 3, 3)), mat, pos=(0.0, 0.0, 0.044 + 0.008 + 0.03 - 0.0003))
    c = w.core
    c.gravity = (9.81 * tilt, 0, -9.81)
    c.localDamping = 0.2
    return w, cube
