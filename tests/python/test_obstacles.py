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
    t1, v1 = O.time, block.velocity() @ down
    O.run(int(0.2 / O.dt), True)
    return (block.velocity() @ down - v1) / (O.time - t1)


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
