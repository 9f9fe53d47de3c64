"""Inverted elements are never carried silently (issue 12, items 2-3).

One tetrahedron of a small block is forced inverted: its corner node (in that
tet only) mirrored through the opposite face, volume ratio -1, the mirror
image of its rest shape.  The Stable Neo-Hookean law (the default) pushes it
back within a few steps and QdemEngine counts and reports the episode;
Saint-Venant-Kirchhoff has a stress-free state there (its mirror state), so
the element would stay inverted, and the engine stops naming it."""
import numpy as np
import pytest

import qdem
from conftest import rubber


def _volumes(p):
    x = p.pos[p.tets]
    return np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0]) / 6


def _invertedBlock(law, world=None):
    """A 10 cm block (2x2x2 cells, 5 tets each) at rest, no gravity, with the
    tet holding corner node 0 mirrored through its opposite face.  Viscosity
    100 Pa s damps the element's own mode (period ~1.4 ms) by ~1/2 of
    critical: the node does not swing back through the inverted state."""
    mat = rubber(young=1e6, viscosity=100.0, law=law)
    p = qdem.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (2, 2, 2), tetsPerCell=5), mat, reorder=False, world=world)
    owners = [t for t in p.tets if 0 in t]
    assert len(owners) == 1  # only that tet is inverted by the move
    x = p.pos
    a, b, c = (x[i] for i in owners[0] if i != 0)
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    x[0] = x[0] - 2 * np.dot(x[0] - a, n) * n
    return p


def test_inverted_element_recovers_and_is_reported(scene, capsys):
    p = _invertedBlock("stableNeoHookean")
    v0 = _volumes(p)
    assert (v0 < 0).sum() == 1
    from yade import ForceResetter, NewtonIntegrator
    scene.engines = [ForceResetter(), qdem.QdemEngine(label="qe", checkPeriod=1, progressPeriod=1),
                     NewtonIntegrator(gravity=(0, 0, 0))]
    scene.dt = 0.5 * qdem.stableDt()["combined"]
    engine = scene.engines[1]
    with pytest.warns(RuntimeWarning, match=r"1 element\(s\) inverted, the first tetrahedron \d+ of piece 0 "
                                             r"\(volume ratio -"):
        scene.run(200, True)
    inv = engine.inverted
    assert inv["max"] == 1 and inv["now"] == 0
    # Back to positive volume within a bounded time: the element's own
    # period is ~ h/c_p = 5 cm / 37 m/s ~ 1.4 ms; it must be out in 10 of them.
    assert 0 < inv["time"] <= 10 * 0.05 / np.sqrt(1e6 * 1.35 / 1000)
    assert inv["first"][:2] == (0, int(np.argmin(v0)))
    vol = _volumes(p)
    assert vol.min() > 0
    # Recovered, not just flipped: the element is back near its own volume.
    assert abs(vol[np.argmin(v0)] / -v0.min() - 1) < 0.2
    out = capsys.readouterr().out
    assert "1 inverted (max 1" in out                       # the progress line while it was inverted
    assert "all inverted elements have recovered" in out
    assert "0 inverted (max 1" in out                       # and after


def test_saint_venant_kirchhoff_inversion_stops_naming_piece_and_element(scene):
    p = _invertedBlock("saintVenantKirchhoff")
    bad = int(np.argmin(_volumes(p)))
    from yade import ForceResetter, NewtonIntegrator
    engine = qdem.QdemEngine(checkPeriod=5)
    scene.engines = [ForceResetter(), engine, NewtonIntegrator(gravity=(0, 0, 0))]
    scene.dt = 0.5 * qdem.stableDt()["combined"]
    with pytest.raises(qdem.StabilityError,
                       match=r"tetrahedron %d of piece 0 is inverted \(volume ratio -1; 1 inverted" % bad) as err:
        for _ in range(200):
            engine.stepOnce()
    assert "Saint-Venant-Kirchhoff element compressed past its limit point" in str(err.value)
    assert "law='stableNeoHookean'" in str(err.value)
    with pytest.raises(RuntimeError, match="tetrahedron %d of piece 0 is inverted" % bad):  # the same in O.run
        scene.run(200, True)


def test_saint_venant_kirchhoff_keeps_a_mirrored_element_inverted():
    """Why the run must stop: left alone, the SVK element stays inverted
    (its mirror state is stress-free), where the default law recovers."""
    for law, stays in (("saintVenantKirchhoff", True), ("stableNeoHookean", False)):
        w = qdem.World()
        p = _invertedBlock(law, world=w)
        bad = int(np.argmin(_volumes(p)))
        w.core.step(0.5 * w.stableDt()["combined"], 2000)
        assert (_volumes(p)[bad] < 0) == stays, law


def test_material_law_is_validated_and_documented():
    assert qdem.QdemMat().law == "stableNeoHookean"
    with pytest.raises(ValueError, match="law='neoHooke' is invalid: must be one of 'stableNeoHookean', "
                                         "'saintVenantKirchhoff'"):
        qdem.QdemMat(law="neoHooke")
    assert "Smith, de Goes" in qdem.QdemMat.law.__doc__
