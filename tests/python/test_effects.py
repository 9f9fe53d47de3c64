"""Only the effects a scene calls for: an effect switched off and an effect whose
value is zero give the same trajectory, to the last bit (issue 6, part 3)."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber


@pytest.fixture(autouse=True)
def oneThread():
    """The comparisons here are to the last bit, which only one thread
    guarantees: on two, the contact loops hand contacts out to the threads
    dynamically, so which thread's buffer (and so the order in which a node's
    forces are summed) can change from run to run, effects or not."""
    before = qdem._core.getThreads()
    qdem._core.setThreads(1)
    yield
    qdem._core.setThreads(before)


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
])
def test_switched_off_equals_zero_valued(zero, off):
    assert np.array_equal(_run(**zero), _run(**off))


def _crossedBars(coreKw, steps=250):
    """Two square bars turned 45 degrees about their axes and crossed, ridge
    over ridge, the top one falling at 0.3 m/s: their only touch is edge-edge
    (the crossing is inside a segment of both ridges).  Returns the top bar's
    lowest ridge height and the most edge-edge contacts seen."""
    import math
    mat = rubber(radius=1e-3, viscosity=200.0)
    w = qdem.World()
    h = 0.01 * math.sqrt(2)
    top = w.addPiece(qdem.boxMesh((0.22, 0.02, 0.02), (11, 1, 1)), mat, pos=(0, 0, h + 1.5e-3),
                     ori=((1, 0, 0), math.pi / 4), vel=(0, 0, -0.3))
    bot = w.addPiece(qdem.boxMesh((0.02, 0.22, 0.02), (1, 11, 1)), mat, pos=(0, 0, -h - 1e-3),
                     ori=((0, 1, 0), math.pi / 4))
    bot.blocked[:] = 7
    top.blocked[:] = 3
    for k, v in coreKw.items():
        setattr(w.core, k, v)
    dt = 0.5 * w.stableDt()["combined"]
    most, low = 0, np.inf
    mid = np.abs(top.refPos[:, 0]) < 0.011
    for _ in range(steps):
        w.core.step(dt, 10)
        most = max(most, w.core.contactCounts["edgeEdge"])
        low = min(low, top.pos[mid, 2].min())
    return low, most, np.vstack([top.pos, top.vel])


def test_edge_edge_switched_off_equals_no_feature_edges_and_differs_from_on():
    """Before, this case ran a scene with no edge-edge contact at all, so off,
    zero and on were trivially equal.  Here the touch is edge-edge only: with
    it on the ridges meet and the top bar stops on the crossing; off (or with
    no feature edges) nothing holds the ridge and it sinks through it."""
    lowOn, nOn, _ = _crossedBars({})
    lowOff, nOff, off = _crossedBars({"edgeEdgeOn": False})
    lowZero, nZero, zero = _crossedBars({"edgeFeatureAngle": math.pi})
    assert nOn > 0 and nOff == 0 and nZero == 0
    assert np.array_equal(off, zero)
    assert lowOn > -1e-3                       # stopped on the lower ridge (top at 0, within the reach)
    assert lowOff < lowOn - 2e-3               # not stopped: sank past it


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


def _stillScene(kind):
    """Two pieces held still (every DOF blocked), already within contact
    reach: crossed square bars ridge over ridge (their touch is edge-edge
    only) or a cube face-down on another (point-polygon)."""
    import math
    mat = rubber(radius=1e-3)
    w = qdem.World()
    if kind == "edgeEdge":
        h = 0.01 * math.sqrt(2)
        a = w.addPiece(qdem.boxMesh((0.22, 0.02, 0.02), (11, 1, 1)), mat, pos=(0, 0, h + 0.5e-3),
                       ori=((1, 0, 0), math.pi / 4))
        b = w.addPiece(qdem.boxMesh((0.02, 0.22, 0.02), (1, 11, 1)), mat, pos=(0, 0, -h - 0.5e-3),
                       ori=((0, 1, 0), math.pi / 4))
    else:
        a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0.01, 0, 0.05 + 1e-3))
        b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, -0.05))
    a.blocked[:] = 7
    b.blocked[:] = 7
    w.core.gravity = (0, 0, 0)
    return w, a


@pytest.mark.parametrize("kind", ["edgeEdge", "pointPolygon"])
def test_contact_kind_switched_on_mid_run_finds_its_contacts_at_once(kind):
    """A contact kind switched on during a run has nothing of its own in the
    broad phase's lists (they were built for the kinds on at the time), and a
    still scene never moves far enough to rebuild them: edge-edge switched on
    later found no contact, ever, and said nothing.  Switching now rebuilds
    the lists, so the kind sees at once what it sees when on from the start."""
    on, aOn = _stillScene(kind)
    late, aLate = _stillScene(kind)
    setattr(late.core, kind + "On", False)
    dt = 1e-6
    on.core.step(dt, 5)
    late.core.step(dt, 5)
    assert on.core.contactCounts[kind] > 0 and late.core.contactCounts[kind] == 0
    setattr(late.core, kind + "On", True)
    for _ in range(3):
        on.core.step(dt, 1)
        late.core.step(dt, 1)
        assert late.core.contactCounts[kind] == on.core.contactCounts[kind]
        # (blocked pieces: the same positions, so the same contact forces)
        assert np.array_equal(late.core.force, on.core.force)
