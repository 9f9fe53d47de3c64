"""A Verlet-list rebuild spread over steps (World.verletRebuildSteps,
doc/contacts.md "Verlet lists"): the nodes not yet done keep their former
lists while the new ones are built a part per step.  The contacts must be
exactly those the cell search finds every step (the seed's case C, which
keeps no lists), whether the scene moves steadily or speeds up in the middle
of a spread rebuild, and the run must equal the one-step rebuild's."""
import numpy as np
import pytest

import qdem
from conftest import rubber


def _slidingCube():
    """A cube sliding and spinning on a fixed one under gravity: steady
    point-polygon contacts whose triangles change as it slides."""
    mat = rubber(radius=5e-3, frictionPiece=0.3)
    w = qdem.World()
    w.core.gravity = (0, 0, -9.81)
    L = 0.1
    bottom = w.addPiece(qdem.boxMesh((3 * L, 3 * L, L), (6, 6, 2)), mat, pos=(0, 0, 0))
    bottom.blocked[:] = 7
    top = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3)), mat, pos=(-0.05, 0, L + 2 * mat.radius - 2e-5),
                     vel=(0.3, 0.1, 0), angVel=(0, 0, 2.0))
    return w, top


def _run(broadPhase, spread, steps, kickAtWindow=None):
    """Steps the scene one step at a time; returns the point-polygon contact
    count of every step, the final positions, and what the lists did.
    kickAtWindow = k: on the step after the first step of the k-th spread
    rebuild, the sliding cube's velocity is multiplied by 40 (the step index
    is returned so that the cell-search run can kick at the same step)."""
    w, top = _slidingCube()
    w.core.broadPhase = broadPhase
    w.core.verletRebuildSteps = spread
    dt = 0.5 * w.stableDt()["combined"]
    counts, kicked, starts = [], None, 0
    what = []  # per step: (the lists' rebuild started, some nodes' lists were built)
    for i in range(steps):
        if isinstance(kickAtWindow, int) and kicked is None and starts >= kickAtWindow:
            kicked = i
            top.vel[:] *= 40
        elif isinstance(kickAtWindow, tuple) and i == kickAtWindow[1]:
            top.vel[:] *= 40
        r0, w0 = w.core.verletRebuilds, w.core.verletWindowSteps
        w.core.step(dt, 1)
        if w.core.verletRebuilds > r0 and w.core.verletWindowOpen:
            starts += 1
        counts.append(w.core.contactCounts["pointPolygon"])
        what.append((w.core.verletRebuilds > r0, w.core.verletWindowSteps > w0))
    info = dict(rebuilds=w.core.verletRebuilds, windowSteps=w.core.verletWindowSteps, kicked=kicked,
                what=np.array(what))
    return np.array(counts), np.array(w.core.pos), info


def test_spread_rebuild_finds_the_cell_search_contacts_every_step():
    ours, posOurs, info = _run(0, 4, 1500)
    seed, posSeed, _ = _run(3, 4, 1500)
    assert (ours > 0).all(), "the cube must touch its support throughout"
    assert info["rebuilds"] >= 5 and info["windowSteps"] >= 2 * info["rebuilds"], info  # most rebuilds spread
    np.testing.assert_array_equal(ours, seed)
    assert np.abs(posOurs - posSeed).max() < 1e-9


def test_spread_rebuild_equals_the_one_step_rebuild():
    spread, posSpread, a = _run(0, 4, 1500)
    one, posOne, b = _run(0, 1, 1500)
    assert a["windowSteps"] > 0 and b["windowSteps"] == 0
    np.testing.assert_array_equal(spread, one)
    assert np.abs(posSpread - posOne).max() <= 1e-12


def test_a_speed_up_during_a_spread_rebuild_finishes_it_at_once():
    """The cube is thrown 40 times faster on the step after a spread rebuild
    started: its former lists would expire before the window ends, so the rest
    of the lists is built at once (or the whole rebuild redone) - never a step
    on lists that have expired: the contacts stay those of the cell search."""
    ours, posOurs, info = _run(0, 4, 700, kickAtWindow=2)
    assert info["kicked"] is not None
    seed, posSeed, _ = _run(3, 4, 700, kickAtWindow=(None, info["kicked"]))
    assert (ours > 0).sum() > 100
    # The kick came on the window's first chunk step (i); at i + 1 the nodes
    # have moved past what the former lists allow: the rest of the lists is
    # built then, or (the new lists' own room exceeded) the rebuild starts
    # over - not a third chunk step at i + 2 as the window would go on.
    i, what = info["kicked"], info["what"]
    assert what[i - 1, 0] and not what[i - 1, 1] and what[i, 1], what[i - 1:i + 3]
    assert what[i + 1].any() and not what[i + 2, 1], what[i - 1:i + 3]
    np.testing.assert_array_equal(ours, seed)
    assert np.abs(posOurs - posSeed).max() < 1e-9


def test_verlet_rebuild_steps_is_a_whole_number_from_1_to_64():
    w = qdem.World()
    w.core.verletRebuildSteps = 8
    assert w.core.verletRebuildSteps == 8
    for bad in (0, 65, 2.5, "4"):
        with pytest.raises((ValueError, TypeError)):
            w.core.verletRebuildSteps = bad
    e = qdem.QdemEngine(world=w)
    e.verletRebuildSteps = 2
    assert e.verletRebuildSteps == 2 and isinstance(e.verletRebuildSteps, int)
    with pytest.raises(ValueError, match="whole number"):
        e.verletRebuildSteps = 1.5


def _slidingCrossedBars(broadPhase, spread, steps=4000):
    """A square bar turned 45 degrees about its axis, lying ridge down across
    the ridges of two held bars (crossed at 90 degrees, 12 cm apart) under
    gravity, and sliding along its axis at 0.3 m/s (y blocked: it slides
    and bounces, but does not roll off): it rests on two edge-edge contacts
    whose crossings run along its ridge over segment ends, while the lists
    are rebuilt every ~200 steps (a spread rebuild registers the edges on
    its second step).  Returns the edge-edge count of every step, the final
    positions and the list counters."""
    import math
    mat = rubber(radius=1e-3, frictionPiece=0.05)
    w = qdem.World()
    w.core.gravity = (0, 0, -9.81)
    h = 0.01 * math.sqrt(2)
    top = w.addPiece(qdem.boxMesh((0.22, 0.02, 0.02), (11, 1, 1)), mat, pos=(-0.02, 0, h + 0.9e-3),
                     ori=((1, 0, 0), math.pi / 4), vel=(0.3, 0, 0))
    top.blocked[:] = 2
    for x in (-0.06, 0.06):
        rail = w.addPiece(qdem.boxMesh((0.02, 0.22, 0.02), (1, 11, 1)), mat, pos=(x, 0, -h - 1e-3),
                          ori=((0, 1, 0), math.pi / 4))
        rail.blocked[:] = 7
    w.core.broadPhase = broadPhase
    w.core.verletRebuildSteps = spread
    w.core.verletSkin = 4.0  # (lists that live long enough to be spread)
    dt = 0.5 * w.stableDt()["combined"]
    counts = []
    for _ in range(steps):
        w.core.step(dt, 1)
        counts.append(w.core.contactCounts["edgeEdge"])
    return np.array(counts), np.array(w.core.pos), dict(rebuilds=w.core.verletRebuilds,
                                                         windowSteps=w.core.verletWindowSteps)


def test_spread_rebuild_finds_the_cell_search_edge_contacts_every_step():
    """Edge-edge under a spread rebuild: the former edge lists serve on the
    window's first step, the new ones (registered on its second) after; the
    contacts are the cell search's at every step and the run equals the
    one-step rebuild's."""
    ours, posOurs, info = _slidingCrossedBars(0, 4)
    one, posOne, infoOne = _slidingCrossedBars(0, 1)
    seed, posSeed, _ = _slidingCrossedBars(3, 4)
    assert (ours >= 2).sum() > 0.5 * len(ours), "the bar must rest on both rails"
    assert info["rebuilds"] >= 10 and info["windowSteps"] >= 1.5 * info["rebuilds"], info  # most spread
    assert infoOne["windowSteps"] == 0
    np.testing.assert_array_equal(ours, seed)
    np.testing.assert_array_equal(ours, one)
    assert np.abs(posOurs - posSeed).max() < 1e-9
    assert np.abs(posOurs - posOne).max() <= 1e-12
