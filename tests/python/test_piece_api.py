"""Piece's quantities follow one rule (doc/materials.md, "Reading a piece"):
what it holds and any no-argument sum or mean over its nodes is a property;
per-element fields and anything with an argument are methods.  The former
method spellings (centroid(), momentum(), velocity(), angularMomentum(about))
still work, with a DeprecationWarning."""
import warnings

import numpy as np
import pytest

import qdem


@pytest.fixture
def piece():
    qdem.reset()
    mat = qdem.QdemMat(young=1e6, density=1000, radius=0.01)
    p = qdem.addPiece(qdem.boxMesh((0.2, 0.3, 0.4), (2, 3, 4)), mat, pos=(1, 2, 3), vel=(0.5, -1, 2),
                      angVel=(0, 0, 3))
    yield p
    qdem.reset()


def test_quantities_are_properties_with_their_rigid_body_values(piece):
    m, x, v = piece.mass, piece.pos, piece.vel
    M = m.sum()
    assert piece.totalMass == pytest.approx(1000 * 0.2 * 0.3 * 0.4, rel=1e-12)
    assert piece.volume == pytest.approx(0.2 * 0.3 * 0.4, rel=1e-12)
    np.testing.assert_allclose(piece.centroid, [1, 2, 3], atol=1e-12)
    np.testing.assert_allclose(piece.momentum, M * np.array([0.5, -1, 2]), rtol=1e-12)
    np.testing.assert_allclose(piece.velocity, [0.5, -1, 2], rtol=1e-12)
    # Spin about z at 3 rad/s: L = sum m r x v about the centre of mass = I_zz w (lumped masses).
    r = x - np.array([1, 2, 3])
    Izz = (m * (r[:, 0] ** 2 + r[:, 1] ** 2)).sum()
    np.testing.assert_allclose(piece.angularMomentum, [0, 0, 3 * Izz], atol=1e-12 * Izz)
    np.testing.assert_allclose(piece.angularMomentumAbout((0, 0, 0)),
                               (np.cross(x, v) * m[:, None]).sum(0), rtol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # the new spellings never warn
        c = piece.centroid + 1.0
        assert type(c) is np.ndarray and type(piece.centroid[2]) is np.float64
        assert np.linalg.norm(piece.velocity) == pytest.approx(np.sqrt(0.25 + 1 + 4))
        assert repr(piece.centroid).startswith("array(")
    for name in ("stress", "vonMises", "surface", "angularMomentumAbout"):
        assert callable(getattr(type(piece), name))


@pytest.mark.parametrize("name", ["centroid", "momentum", "velocity", "angularMomentum"])
def test_old_method_spellings_warn_and_give_the_same_values(piece, name):
    with pytest.warns(DeprecationWarning, match=r"Piece\.%s\(\) is deprecated" % name):
        old = getattr(piece, name)()
    np.testing.assert_array_equal(old, getattr(piece, name))
    assert type(old) is np.ndarray


def test_old_angular_momentum_about_a_point_warns_and_names_the_new_method(piece):
    with pytest.warns(DeprecationWarning, match=r"angularMomentumAbout\(point\)"):
        old = piece.angularMomentum(about=(0, 0, 0))
    np.testing.assert_allclose(old, piece.angularMomentumAbout((0, 0, 0)), rtol=1e-15)
    with pytest.warns(DeprecationWarning):
        np.testing.assert_allclose(piece.angularMomentum((0, 0, 0)), old, rtol=1e-15)
