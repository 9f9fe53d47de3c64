"""Adaptive rigidity's wake test weighs a load change by the strain it would
make (QdemEngine.rigidWakeStrain; doc/formulation.md "Adaptive rigidity",
"When it deforms again").

* A brick rocking on a floor shifts its weight from edge to edge: a large
  relative change of its load that hardly strains it.  With the relative
  test alone (rigidWakeStrain = 0) it switched rigid -> deformable -> rigid
  about 150 times in 0.6 s; with the strain test it switches only at the
  slaps of its face on the floor (real impacts, default 1e-5), or once
  (1e-4, above the slaps' strain), and its centre follows the
  all-deformable run's to 1 mm (its rocking travel: 7 mm).
* A real hit (a block sliding into the rigid one at 1 m/s) wakes it the
  same step as the relative test alone, within a few steps of the first
  touch."""
import math

import numpy as np
import pytest

import qdem
from conftest import rubber

G = 9.81
W, H = 0.06, 0.12          # the rocking brick: 6 x 6 x 12 cm
STIFF = 1e9                # Pa: its weight strains it by rho g H / E ~ 1e-6


def _floor(w):
    o = qdem._core.Obstacle()
    o.kind, o.bodyId, o.axis, o.sense = 0, 0, 2, 1
    w.core.setObstacles([o])
    w.core.setObstacleStates(np.array([[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0.0]]))


def _settings(w, strain):
    w.core.rigidStrainRate = 0.5
    w.core.rigidTime = 0.005
    if strain is not None:
        w.core.rigidWakeStrain = strain


def _rocking(rigid, strain=None, duration=0.6):
    """The brick settled on a floor (friction 0.8), then tipped about one
    bottom edge with 30 % of the energy that would tip it over: it rocks
    about its edges and slaps down on its face, the rocking dying out.
    Returns (time, centre y, centre z, rigid) every 20 steps and the switches."""
    w = qdem.World()
    w.core.gravity = (0, 0, -G)
    mat = rubber(young=STIFF, radius=2e-3, viscosity=0.0, frictionWall=0.8, restitution=0.5)
    b = w.addPiece(qdem.boxMesh((W, W, H), (2, 2, 4)), mat, pos=(0, 0, H / 2 + mat.radius))
    _floor(w)
    _settings(w, strain)
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.05 / dt))
    x, m = b._nodes("pos"), b.mass
    r = x - np.array([0, W / 2, x[:, 2].min()])
    energy = 0.3 * m.sum() * G * (math.hypot(W / 2, H / 2) - H / 2)
    omega = math.sqrt(2 * energy / (m * (r[:, 1] ** 2 + r[:, 2] ** 2)).sum())
    b.vel[:] = np.cross([-omega, 0, 0], r)
    w.core.rigidify = rigid
    t0, out = w.core.time, []
    while w.core.time - t0 < duration:
        w.core.step(dt, 20)
        c = (b._nodes("pos") * m[:, None]).sum(axis=0) / m.sum()
        out.append((w.core.time - t0, c[1], c[2], b.rigid))
    return np.array(out, dtype=float), w.core.rigidSwitches


def test_rocking_brick_no_longer_thrashes_and_follows_the_deformable_run():
    ref, _ = _rocking(False)
    assert np.ptp(ref[:, 1]) > 5e-3, "the brick must really rock"
    old, oldSwitches = _rocking(True, strain=0.0)
    new, newSwitches = _rocking(True)
    quiet, quietSwitches = _rocking(True, strain=1e-4)
    print("switches: relative test alone %d, default %d, 1e-4 %d; rigid share %.2f %.2f %.2f" % (
        oldSwitches, newSwitches, quietSwitches, old[:, 3].mean(), new[:, 3].mean(), quiet[:, 3].mean()))
    # Seen: 84-149 (relative test alone), 15 (default), 1 (1e-4).
    assert oldSwitches > 50, oldSwitches
    assert newSwitches <= 20, newSwitches
    assert quietSwitches <= 2, quietSwitches
    assert new[:, 3].mean() > 1.5 * old[:, 3].mean()          # rigid for more of the time (0.65 against 0.34)
    assert quiet[:, 3].mean() > 0.95
    for tr in (old, new, quiet):
        assert np.abs(tr[:, 1:3] - ref[:, 1:3]).max() < 1e-3  # centre within 1 mm of the deformable run's


def _slide(strain, limit=4000):
    """Block A (stiff) sliding at 1 m/s on a frictionless floor into block B
    resting rigid 5 mm ahead: (step of the first touch, step B wakes, the
    strain estimate of B's load change then)."""
    w = qdem.World()
    w.core.gravity = (0, 0, -G)
    mat = rubber(young=STIFF, radius=2e-3, viscosity=0.0, frictionWall=0.0, frictionPiece=0.3)
    a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(-0.105 - 2 * mat.radius, 0, 0.05 + mat.radius))
    b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (3, 3, 3)), mat, pos=(0, 0, 0.05 + mat.radius))
    _floor(w)
    _settings(w, strain)
    dt = 0.8 * w.stableDt()["combined"]
    w.core.step(dt, int(0.03 / dt))       # settled, both at rest
    w.core.rigidify = True
    w.core.step(dt, int(0.02 / dt))
    assert b.rigid, "the block at rest must be rigid before the hit"
    a.vel[:] = (1.0, 0, 0)
    touch = None
    for k in range(limit):
        w.core.step(dt, 1)
        if touch is None and abs(b.force[:, 0].sum()) > 0:
            touch = k
        strain = w.core.rigidLoadStrain(1)   # (kept when it wakes: the wake step's)
        if not b.rigid:
            return touch, k, strain
    raise AssertionError("the hit did not wake the block (first touch at step %s)" % touch)


def test_a_real_hit_wakes_the_rigid_piece_the_step_it_comes():
    touch0, wake0, _ = _slide(0.0)
    touch, wake, strain = _slide(None)
    assert touch == touch0 and touch is not None
    assert wake == wake0, (wake, wake0)        # the same step as the relative test alone
    assert wake - touch <= 3, (touch, wake)
    print("first touch at step %d, woken at step %d (relative test alone: %d); strain of the change %.3g" % (
        touch, wake, wake0, strain))
    touch1, wake1, _ = _slide(1e-4)
    assert wake1 == wake0, (wake1, wake0)      # a hit at 1 m/s strains it by far more than 1e-4
