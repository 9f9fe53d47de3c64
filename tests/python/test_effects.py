"""Only the effects a scene calls for: an effect switched off and an effect whose
value is zero give the same trajectory, to the last bit (issue 6, part 3)."""
import numpy as np
import pytest

import qdem
from conftest import rubber


def _run(matKw=None, coreKw=None, steps=1500):
    w = qdem.World()
    mat = rubber(radius=2e-3, **(matKw or {}))
    a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(-0.06, 0.02, 0), vel=(0.5, 0, 0),
                   angVel=(0, 3, 5))
    b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0.06, -0.01, 0.01), ori=((1, 2, 3), 0.5),
                   vel=(-0.5, 0, 0))
    for k, v in (coreKw or {}).items():
        setattr(w.core, k, v)
    w.core.step(2e-6, steps)
    assert w.core.contactCounts["pointPolygon"] > 0 or steps < 100
    return np.vstack([a.pos, b.pos, a.vel, b.vel])


@pytest.mark.parametrize("zero, off", [
    ({"matKw": {"viscosity": 0.0}}, {"matKw": {"viscosity": 300.0}, "coreKw": {"viscosityOn": False}}),
    ({"matKw": {"frictionPiece": 0.0}}, {"matKw": {"frictionPiece": 0.4}, "coreKw": {"frictionOn": False}}),
    ({"coreKw": {"edgeFeatureAngle": 3.2}}, {"coreKw": {"edgeEdgeOn": False}}),
])
def test_switched_off_equals_zero_valued(zero, off):
    assert np.array_equal(_run(**zero), _run(**off))


def test_energy_tracking_does_not_change_the_dynamics():
    assert np.array_equal(_run(coreKw={"trackEnergy": True}), _run(coreKw={"trackEnergy": False}))


def test_pieces_out_of_reach_run_no_contact_code():
    w = qdem.World()
    mat = rubber()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0))
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(1, 0, 0))
    w.core.step(1e-6, 10)
    t = w.core.timings
    assert t["pointPolygon"] == 0 and t["edgeEdge"] == 0
    assert w.core.verletRebuilds == 0
