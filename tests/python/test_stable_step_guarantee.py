"""The stable step is a guarantee, never optimistic: the scenes where it was
(doc/formulation.md, section 3; the property test tests/cpp/
test_stable_step_property.cpp samples thousands of states).

- A light, stiff YADE sphere resting on a held slab: its spring acts on the
  ball's rolling mass 2m/7 (tangential) and its dashpot, lagged half a step,
  lowers the limit.  On the undamped normal-only bound it chattered at
  0.09-0.25 m/s at 0.8-0.9 of stableTimeStep().
- One regular tetrahedron stretched 10 % isotropically: the stable
  Neo-Hookean law stiffens (its highest frequency squared grows 1.73x); a
  filter that said 1.46 passed dt = 0.78 of the reference limit, where the
  element blows up.
"""
import numpy as np
import pytest

import qdem


def _restingSphere(O, friction, e=0.3):
    from yade import FrictMat, utils
    from test_spheres import _engines
    mat = qdem.QdemMat(young=1e9, poisson=0.3, density=2000.0, viscosity=0.0, radius=0.002, restitution=e,
                       frictionPiece=friction)
    slab = qdem.addPiece(qdem.boxMesh((0.2, 0.2, 0.04), (10, 10, 2)), mat, pos=(0, 0, 0.022))
    slab.blocked[:] = 7  # held
    fm = O.materials.append(FrictMat(young=1e9, poisson=0.3, frictionAngle=float(np.arctan(friction)), density=100))
    R = 0.005
    # Touching the contact surface (slab top 0.042 m + its radius), not pressed in.
    sid = O.bodies.append(utils.sphere((0.013, 0.007, 0.044 + R), R, material=fm))
    O.engines = _engines(gravity=(0, 0, -9.81))
    return sid


@pytest.mark.parametrize("friction", [0.0, 0.5])
@pytest.mark.parametrize("fraction", [0.8, 0.95])
def test_a_light_stiff_sphere_resting_on_a_held_slab_stays_at_rest(scene, friction, fraction):
    from yade import Vector3
    O = scene
    sid = _restingSphere(O, friction)
    O.dt = fraction * O.engines[3].stableTimeStep()
    O.step()
    O.bodies[sid].state.vel = Vector3(2e-4, 1e-4, -1e-3)  # a nudge: every mode excited
    speeds = []
    for i in range(4000):
        O.step()
        if i >= 3500:
            speeds.append(O.bodies[sid].state.vel.norm())
    # The nudge's sideways part (2.2e-4 m/s) may stay (it slides, or rolls
    # at 5/7 of it); the vertical part is damped out (restitution 0.3).
    assert max(speeds) < 3e-4, "the sphere chatters at %.3g m/s" % max(speeds)
    z = O.bodies[sid].state.pos[2]
    assert z == pytest.approx(0.044 + 0.005, abs=1e-5)  # still resting on the slab


def test_a_stretched_tetrahedron_is_refused_at_a_step_its_stiffened_shape_cannot_take(scene):
    mat = qdem.QdemMat(young=1e6, poisson=0.3, density=1000, viscosity=0.0, radius=0.01)
    regular = 0.1 * np.array([[0, 0, 0], [1, 0, 0], [0.5, 0.866025, 0], [0.5, 0.288675, 0.816497]])
    mesh = qdem.Mesh(regular, np.array([[0, 1, 2, 3]]))
    p = qdem.addPiece(mesh, mat)
    core = p.world.core
    ref = core.stableDt()["combined"]
    p.pos[:] = 1.1 * (p.refPos - p.refPos.mean(axis=0)) + p.refPos.mean(axis=0)
    with pytest.raises(qdem.StabilityError, match="strained .* stable time step on the current shape is"):
        core.checkCurrentDt(0.78 * ref)
    # The largest step the check accepts on this shape: the element's tangent
    # at F = 1.1 I has 1.73x the reference omega^2 (for one element, the
    # current-shape check is exact), so 1/sqrt(1.73) = 0.760 of the reference.
    lo, hi = 0.0, ref
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        try:
            core.checkCurrentDt(mid)
            lo = mid
        except qdem.StabilityError:
            hi = mid
    assert lo / ref == pytest.approx(1 / np.sqrt(1.73), rel=0.01)
    p.pos[:] = p.refPos
    core.checkCurrentDt(0.99 * ref)  # at rest: the reference step
