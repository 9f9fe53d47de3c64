"""Shogi piece generator (seed §5): shape, proportions and meshes."""
import math

import numpy as np
import pytest

import qdem
from qdem.scenes import shogi


def _angles(p):
    out = []
    for i in range(5):
        a, b, c = p[i - 1], p[i], p[(i + 1) % 5]
        u, v = a - b, c - b
        out.append(math.degrees(math.acos(u @ v / np.linalg.norm(u) / np.linalg.norm(v))))
    return out


@pytest.mark.parametrize("kind", shogi.ORDER)
def test_outline_has_the_shogi_angles_and_size(kind):
    h, w, t = shogi.KINDS[kind]
    p = shogi.outline(h, w)
    assert np.allclose(sorted(_angles(p)), [81, 81, 117, 117, 144], atol=1e-9)
    assert p[:, 1].max() == pytest.approx(h) and np.ptp(p[:, 0]) == pytest.approx(w)


# The seed paper's pieces (its §5), stated here, not taken from the generator:
# king 32.0 x 28.7 x 9.7 mm, pawn 27.0 x 22.5 x 7.75 mm (height x width x base
# thickness), interior angles 81, 81, 117, 117, 144 degrees, about 797 nodes and
# 2,566 tetrahedra per piece.
PAPER = {"king": (32.0, 28.7, 9.7), "pawn": (27.0, 22.5, 7.75)}


def test_sizes_run_from_king_to_pawn():
    """Measured on the generated meshes: bounding box = the paper's sizes."""
    for kind, (h, w, t) in PAPER.items():
        lo, hi = shogi.mesh(kind).bounds()
        assert (hi - lo) * 1e3 == pytest.approx([w, h, t], rel=0.01)
    heights = [np.ptp(shogi.surface(k)[0][:, 1]) for k in shogi.ORDER]
    assert heights == sorted(heights, reverse=True)
    assert len(shogi.SET) == 20 and shogi.SET.count("pawn") == 9


@pytest.mark.parametrize("kind", ["king", "gold", "pawn"])
def test_meshed_pieces_are_valid_with_the_seeds_counts(kind):
    m = shogi.mesh(kind)
    assert (m.volumes() > 0).all()
    m.check()                                            # closed, manifold surface
    assert m.nNodes == pytest.approx(797, rel=0.10)
    assert m.nTets == pytest.approx(2566, rel=0.10)
    # The volume the piece's closed surface encloses (divergence theorem over its
    # triangles), not the generator's own formula: the mesh fills the surface...
    v, tris = shogi.surface(kind)
    enclosed = np.einsum("ij,ij->i", v[tris[:, 0]], np.cross(v[tris[:, 1]], v[tris[:, 2]])).sum() / 6
    assert m.volumes().sum() == pytest.approx(enclosed, rel=0.01)
    assert shogi.volume(kind) == pytest.approx(enclosed, rel=1e-12)   # ...and volume() is that volume
    lo, hi = m.bounds()
    if kind in PAPER:                                    # the paper's sizes, measured
        h, w, t = PAPER[kind]
        assert (hi - lo) * 1e3 == pytest.approx([w, h, t], rel=0.01)
    h, w, t = (v * 1e-3 for v in shogi.KINDS[kind])
    top = m.nodes[:, 1] > 0.95 * h                       # thinner at the top
    base = m.nodes[:, 1] < 0.05 * h
    assert np.ptp(m.nodes[top, 2]) < 0.8 * np.ptp(m.nodes[base, 2])


def test_two_pieces_topple_and_momentum_balances_with_the_floor(scene):
    """A pushed rook tips over onto a second one.  Momentum of the pair changes
    exactly by gravity plus the floor's reaction (summed every step)."""
    from yade import ForceResetter, NewtonIntegrator, PyRunner, utils
    O = scene
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4, restitution=0.5,
                       frictionPiece=0.1, frictionWall=0.5)
    a, b = shogi.dominoLine(["rook", "rook"], mat, spacing=0.6, push=10.0)
    floor = O.bodies.append(utils.wall(0, axis=2, sense=1))
    g = np.array([0, 0, -9.81])
    impulse = np.zeros(3)
    touched, pushed = [], []

    def ledger():
        nonlocal impulse
        f = O.forces.f(floor)
        impulse += (-np.array([f[0], f[1], f[2]]) + (a.totalMass + b.totalMass) * g) * O.dt
        touched.append(qdem.defaultWorld().core.contactCounts["pointPolygon"])
        pushed.append(b.velocity[0])

    import builtins
    builtins._qdemLedger = ledger
    O.engines = [ForceResetter(), qdem.QdemEngine(), PyRunner(command="_qdemLedger()", iterPeriod=1, initRun=True),
                 NewtonIntegrator(gravity=tuple(g))]
    O.dt = 0.8 * O.engines[1].stableDt()["combined"]
    # the ledger uses the velocities at half steps: compare momenta the same way
    p0 = a.momentum + b.momentum
    O.run(int(0.08 / O.dt), True)
    p1 = a.momentum + b.momentum
    del builtins._qdemLedger
    assert max(touched) > 0                                  # the pieces met
    assert max(pushed) > 0.02                                # ... and the second one was pushed (0.024 m/s)
    scale = np.abs(impulse).max()
    assert np.abs((p1 - p0) - impulse).max() < 1e-6 * scale


@pytest.mark.parametrize("name", ["two_rooks", "king_pawns"])   # forty: a plain line
def test_scenes_start_with_pieces_apart(name):
    """No two pieces of a scene overlap (nor touch) at the start."""
    w = qdem.World()
    mat = qdem.QdemMat(young=2e6, poisson=0.3, density=700, viscosity=0.0, radius=5e-4)
    pieces = shogi.scene(name, mat, 1.0, world=w)
    w.core.step(1e-9, 1)
    assert w.core.contactCounts["pointPolygon"] + w.core.contactCounts["edgeEdge"] == 0
    assert len(pieces) == len(shogi.SCENES[name]["kinds"])
