"""What the core schedules for QdemEngine: the version of the inputs of the
stable step (World::stableStepVersion: QdemEngine checks O.dt again exactly
when it or that version changed) and the periodic checks in one call
(World::periodicChecks).  Before, the engine kept the dt check under a key
written by hand (O.dt, pieces, viscosity, viscousIntegration, friction,
frictionModel, spheres): 4 of the 21 settings; a setting added later that
moves the stable step had to be remembered there."""
import math

import numpy as np
import pytest

import qdem
from qdem import _core


def _otherValue(core, decl):
    """A value of the setting other than its present one, that the core accepts."""
    name, old = decl["name"], getattr(core, decl["name"])
    if decl["kind"] == "bool":
        return not old
    if decl["kind"] == "choice":
        return (old + 1) % len(decl["choices"])
    for v in (old * 1.5, old + 1, old * 0.5, old - 0.5 * (old - decl["lo"]), 0.5 * (decl["lo"] + decl["hi"])):
        if decl["kind"] == "integer":
            v = int(round(v))
        if not math.isfinite(v) or v == old:
            continue
        try:
            setattr(core, name, v)
        except ValueError:
            continue
        setattr(core, name, old)
        return v
    raise AssertionError("no other value found for %s" % name)


def test_every_setting_moves_the_stable_step_version():
    """Each declared setting, changed, gives a new version, and setting it
    back another; asking again without a change gives the same one."""
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat())
    core = w.core
    missed = []
    for decl in _core.settings:
        v0 = core.stableStepVersion
        assert core.stableStepVersion == v0
        old = getattr(core, decl["name"])
        setattr(core, decl["name"], _otherValue(core, decl))
        v1 = core.stableStepVersion
        setattr(core, decl["name"], old)
        if not (v1 != v0 and core.stableStepVersion != v1):
            missed.append(decl["name"])
    assert not missed, "settings whose change leaves the stable step's version: %s" % missed


def test_pieces_materials_and_obstacles_move_the_version():
    w = qdem.World()
    core = w.core
    v = core.stableStepVersion
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat())
    assert core.stableStepVersion != v
    v = core.stableStepVersion
    wall = _core.Obstacle()
    wall.kind, wall.axis, wall.sense = 0, 2, 1
    core.setObstacles([wall])
    assert core.stableStepVersion != v
    v = core.stableStepVersion
    core.setObstacles([wall])  # set again (YADE made it dynamic, or another body took its id): checked again
    assert core.stableStepVersion != v


def test_o_dt_is_checked_again_when_a_setting_lowers_the_stable_step(scene):
    """QdemEngine: O.dt between the implicit and the explicit viscous limit
    runs with viscousIntegration='implicit'; switching to 'explicit' mid-run
    stops the next step with StabilityError naming the viscous limit."""
    from yade.wrapper import ForceResetter, NewtonIntegrator
    O = scene
    mat = qdem.QdemMat(young=1e6, viscosity=2e3, density=1000, radius=0.01)
    qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.2))
    qe = qdem.QdemEngine(viscousIntegration="implicit")
    O.engines = [ForceResetter(), qe, NewtonIntegrator(gravity=(0, 0, 0))]
    d = qe.stableDt()
    assert d["combinedExplicit"] < 0.5 * d["combinedImplicit"]
    O.dt = 0.5 * (d["combinedExplicit"] + d["combinedImplicit"])
    O.run(5, True)
    qe.viscousIntegration = "explicit"
    with pytest.raises(qdem.StabilityError, match="viscous"):
        O.run(1, True)


def test_periodic_checks_run_every_check_period_only():
    """core.periodicChecks runs the checks when core.iter is a multiple of
    checkPeriod (never at 0), returning what the counting checks found, and
    raises what a check raises only then."""
    w = qdem.World()
    w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2)), qdem.QdemMat())
    core = w.core
    dt = 0.5 * w.stableDt()["combined"]
    ran = []
    for _ in range(7):
        core.step(dt)
        r = core.periodicChecks(3, 1, dt, True)
        if r is not None:
            ran.append(core.iter)
            assert r["inverted"]["count"] == 0 and r["edges"]["count"] == 0
    assert ran and all(i % 3 == 0 for i in ran) and len(ran) in (2, 3), ran
    assert core.periodicChecks(0, 0, dt, True) is None
    core.pos[0, 0] = np.nan
    core.iter = 7
    assert core.periodicChecks(3, 1, dt, True) is None  # (not due: nothing read)
    core.iter = 9
    with pytest.raises(qdem.StabilityError):
        core.periodicChecks(3, 1, dt, True)
