"""Pieces too soft for their load do not pass through each other silently.

The contact spring is kn ~ E r per node and sees a node only within its
reach r_a + r_b of the other piece's surface.  A very soft cube on a stiff
one, or a stiff cube crushing a very soft one against the floor, pushes
nodes deeper than that: no contact pushes them back, and before this check
the pieces interpenetrated for good with no error (the soft cube of the
first scene ended below the floor inside the stiff one).  Every check period
a surface node lying inside another piece deeper than the reach now stops
the run with a StabilityError naming both pieces, the node, its depth
against the reach and the fixes (PieceStartOverlap.cpp, doc/hard_cases.md
"Deep overlap").  Stacks whose contacts hold the weight run untouched."""
import numpy as np
import pytest

import qdem

H = 0.2  # cube side [m]
R = 0.01  # node radius [m]: reach r_a + r_b = 2 cm


def _stack(O, eBottom, eTop, damping, offset):
    from yade import ForceResetter, NewtonIntegrator, utils

    def mat(E):
        return qdem.QdemMat(young=E, poisson=0.3, density=1000, viscosity=0, radius=R, restitution=0.3)

    mesh = qdem.boxMesh((H, H, H), (4, 4, 4))
    bottom = qdem.addPiece(mesh, mat(eBottom), pos=(0, 0, H / 2 + R))
    top = qdem.addPiece(mesh, mat(eTop), pos=(offset, offset / 3, 1.5 * H + 3 * R))
    O.bodies.append(utils.wall(0, axis=2, sense=1))
    O.engines = [ForceResetter(), qdem.QdemEngine(label="qe", damping=damping, threads=1),
                 NewtonIntegrator(gravity=(0, 0, -9.81))]
    O.dt = 0.5 * O.engines[1].stableTimeStep()
    return bottom, top


def _nodesInside(p, q):
    """Surface nodes of p inside q's closed surface (winding number)."""
    T = q.surface()["triangles"]
    out = 0
    for x in p.pos[p.surface()["nodes"]]:
        a, b, c = (q.pos[T[:, k]] - x for k in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb \
            + np.einsum("ij,ij->i", b, c) * la
        out += abs(2 * np.arctan2(num, den).sum() / (4 * np.pi)) > 0.5
    return out


MESSAGE = (r"piece [01] has sunk into piece [01] deeper than their contact can see: node \d+ of piece [01] .* is "
           r"0\.0\d+ m inside piece [01], beyond the contact reach r_a \+ r_b = 0\.01 \+ 0\.01 = 0\.02 m.*"
           r"interpenetrate for good.*stiffer material.*larger radius r so that the reach covers the overlap.*"
           r"smaller impact speed.*finer mesh")


def test_a_very_soft_cube_sinking_into_a_stiff_one_stops_the_run(scene):
    # The tester's stack2 (E 1e4 on 1e7, damping 0.3): it sank through the
    # stiff cube and below the floor by t = 1.1 s.
    _stack(scene, eBottom=1e7, eTop=1e4, damping=0.3, offset=0.03)
    with pytest.raises(qdem.StabilityError, match=MESSAGE):
        scene.run(int(0.8 / scene.dt), True)
    assert 0.3 < scene.time < 0.8


def test_a_stiff_cube_crushing_a_very_soft_one_stops_the_run(scene):
    # E 1e7 on 3e3: the soft cube is crushed below the floor under the stiff one.
    _stack(scene, eBottom=3e3, eTop=1e7, damping=0.0, offset=0.0)
    with pytest.raises(qdem.StabilityError, match=MESSAGE):
        scene.run(int(0.7 / scene.dt), True)


@pytest.mark.parametrize("eBottom, eTop, damping, offset", [
    (1e7, 1e7, 0.3, 0.03),  # a stiff stack
    (3e4, 1e7, 0.0, 0.0),   # stiff on soft, centred: the contact holds it, bouncing
    (3e4, 1e7, 0.0, 0.03),  # the tester's stack3: the stiff cube tips off the soft one onto the floor
])
def test_stacks_whose_contact_holds_the_load_run_untouched(scene, eBottom, eTop, damping, offset):
    bottom, top = _stack(scene, eBottom, eTop, damping, offset)
    for _ in range(8):
        scene.run(int(0.1 / scene.dt), True)
        assert _nodesInside(top, bottom) == 0 and _nodesInside(bottom, top) == 0


def test_pieces_started_interpenetrated_are_let_separate():
    """Two cubes started 30 % into each other (accepted at the start: the
    contact sees nodes inside and pushes them apart, test_hard_cases.py):
    nodes still deeper than the reach at the first checks do not stop the
    run; the pair is watched like any other once it is out."""
    from conftest import rubber
    L, frac = 0.1, 0.3
    w = qdem.World()
    mat = rubber(radius=2e-3, viscosity=100.0, young=1e7)
    a = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3), 5), mat, pos=(-(1 - frac) * L / 2, 0, 0))
    b = w.addPiece(qdem.boxMesh((L, L, L), (3, 3, 3), 5), mat, pos=((1 - frac) * L / 2, 0.013, 0.007))
    # (0.7: pressed this deep, the contacts as they are lower the step by
    # ~20 % against the estimate before the run, and the run would stop)
    dt = 0.7 * w.stableDt()["combined"]
    for _ in range(15):
        w.core.step(dt, 100)
        w.core.checkDeepOverlap()
    assert b.pos[:, 0].min() > a.pos[:, 0].max()
    # Out of each other and watched again: centres put half a side apart, it is named.
    b.pos[:] += a.centroid - b.centroid + np.array([0.5 * L, 0, 0])
    with pytest.raises(qdem.StabilityError, match=r"piece [01] has sunk into piece [01] deeper"):
        w.core.step(dt, 1)  # (the contact phase sees it in that step: ContactDepthCheck.cpp)
        w.core.checkDeepOverlap()
