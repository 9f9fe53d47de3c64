"""Contact options of the accuracy study (doc/accuracy.md): each changes what
it should and nothing else.

* pointPolygonRegions=False is the seed's inside test (§3.1): a node over a
  face interior feels exactly the same force, a node in the region of a
  convex edge feels none (with the regions: kn x overlap along the normal
  from the edge).
* frictionModel='regularized': the same Coulomb force mu Fn while sliding,
  but a creep at vReg tan(theta)/mu on a slope the spring law holds."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber


def _stylus(w, mat, apex, direction):
    """A one-tet stylus with its apex at `apex`, pointing away along `direction`."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    u = np.cross(d, (0, 1, 0) if abs(d[1]) < 0.9 else (1, 0, 0))
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    s = 0.03
    nodes = np.array([apex, apex + 2 * s * d + s * u, apex + 2 * s * d - 0.5 * s * u + s * v,
                      apex + 2 * s * d - 0.5 * s * u - s * v])
    tet = [0, 1, 2, 3] if qdem.Mesh(nodes, [[0, 1, 2, 3]], check=False).volumes()[0] > 0 else [0, 2, 1, 3]
    return w.addPiece((nodes, [tet]), mat, reorder=False)


def _apexForce(regions, apex, direction):
    mat = rubber(radius=2e-3, frictionPiece=0.0, restitution=1.0)
    w = qdem.World()
    slab = w.addPiece(qdem.boxMesh((0.3, 0.3, 0.05), (6, 6, 1)), mat, pos=(0, 0, -0.025))  # top face z = 0
    stylus = _stylus(w, mat, np.asarray(apex, float), direction)
    slab.blocked[:] = 7
    stylus.blocked[:] = 7
    w.core.pointPolygonRegions = regions
    w.core.step(1e-7, 1)
    # The apex's contact stiffness carries its area weight (doc/contacts.md).
    return stylus.force[0].copy(), w.core.contactCounts["pointPolygon"], mat, stylus.contactWeight[0]


def test_seed_inside_test_drops_edge_region_contacts_only():
    # Over the face interior: the same force, to the bit, with or without regions.
    above = [0.013, 0.027, 3e-3]
    f1, n1, mat, wA = _apexForce(True, above, (0, 0, 1))
    f0, n0, _, _ = _apexForce(False, above, (0, 0, 1))
    kn = wA * mat.young * mat.radius
    assert n1 == n0 == 1
    assert np.array_equal(f1, f0)
    assert f1 == pytest.approx([0, 0, kn * (2 * mat.radius - 3e-3)], abs=1e-9 * kn * 1e-3)
    # Beside the slab's convex top edge (x = 0.15, z = 0), 3 mm from it along
    # the diagonal: only the edge region sees it.
    dist = 3e-3
    n = np.array([1.0, 0, 1.0]) / math.sqrt(2)
    apex = np.array([0.15, 0.025, 0.0]) + dist * n
    f1, n1, _, _ = _apexForce(True, apex, n)
    f0, n0, _, _ = _apexForce(False, apex, n)
    assert n1 == 1 and n0 == 0
    assert np.abs(f0).max() < 1e-9 * kn * dist    # rounding of the stylus' own element force
    assert f1 == pytest.approx(kn * (2 * mat.radius - dist) * n, rel=1e-6)


def _block(model, slope=0.0, v0=0.0, mu=0.3, vReg=1e-3):
    mat = rubber(radius=2e-3, viscosity=2000.0, frictionPiece=mu)
    w = qdem.World()
    slab = w.addPiece(qdem.boxMesh((0.4, 0.2, 0.05), (8, 4, 1)), mat, pos=(0.1, 0, -0.025))
    slab.blocked[:] = 7
    block = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), mat, pos=(0, 0, 0.05 + 2 * mat.radius),
                       vel=(v0, 0, 0))
    w.core.gravity = (9.81 * math.sin(slope), 0, -9.81 * math.cos(slope))
    w.core.frictionModel = {"spring": 0, "regularized": 1}[model]
    w.core.frictionRegVelocity = vReg
    return w, block, 0.8 * w.stableDt()["combined"]


@pytest.mark.parametrize("model", ["spring", "regularized"])
def test_both_friction_models_slide_at_mu_g(model):
    w, block, dt = _block(model, v0=0.6)
    w.core.step(dt, int(0.02 / dt))
    t1, v1 = w.core.time, block.velocity[0]
    w.core.step(dt, int(0.1 / dt))
    t2, v2 = w.core.time, block.velocity[0]
    assert v2 > 0.1
    assert (v1 - v2) / (t2 - t1) == pytest.approx(0.3 * 9.81, rel=0.02)


def test_regularized_friction_creeps_on_a_slope_the_spring_holds():
    mu, vReg = 0.3, 2e-3
    theta = math.atan(mu / 2)                      # half the friction angle
    creep = {}
    for model in ("spring", "regularized"):
        w, block, dt = _block(model, slope=theta, mu=mu, vReg=vReg)
        # Past the landing's elastic rocking (its up-and-down-slope swing is
        # still +-1.5e-5 m/s at 0.1 s, and its phase depends on the mesh).
        w.core.step(dt, int(0.16 / dt))
        x0, t0 = block.centroid[0], w.core.time
        w.core.step(dt, int(0.1 / dt))
        creep[model] = (block.centroid[0] - x0) / (w.core.time - t0)
    assert abs(creep["spring"]) < 1e-5
    assert creep["regularized"] == pytest.approx(vReg * math.tan(theta) / mu, rel=0.05)


def test_friction_models_agree_without_friction():
    """mu = 0: the model is never consulted; trajectories are identical to the bit."""
    out = []
    for model in ("spring", "regularized"):
        w, block, dt = _block(model, v0=0.6, mu=0.0)
        w.core.step(dt, 300)
        out.append(block.pos.copy())
    assert np.array_equal(out[0], out[1])


def test_engine_attributes_reach_the_core():
    # not the `scene` fixture: it leaves 2 threads set for the tests after this one
    from yade import O, ForceResetter, NewtonIntegrator
    O.reset()
    qdem.reset()
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), rubber())
    e = qdem.QdemEngine(frictionModel="regularized", frictionRegVelocity=0.02, pointPolygonRegions=False)
    O.engines = [ForceResetter(), e, NewtonIntegrator()]
    O.dt = 0.5 * e.stableDt()["combined"]
    O.step()
    core = qdem.defaultWorld().core
    assert (core.frictionModel, core.frictionRegVelocity, core.pointPolygonRegions) == (1, 0.02, False)
    with pytest.raises(ValueError, match="frictionModel"):
        qdem.QdemEngine(frictionModel="coulomb")
    with pytest.raises(ValueError):
        core.frictionModel = 2
    O.reset()
    qdem.reset()
