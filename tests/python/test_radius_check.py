"""A contact radius larger than half a piece's thickness (the seed's 0.04 m,
meant for its 766x pieces, on a real-size part) is named at addPiece with the
thickness, the radius and the fix (doc/getting_started.md, choosing parameters)."""
import warnings

import numpy as np
import pytest

import qdem


def _rotation(angle, axis):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _radiusWarnings(mesh, radius, ori=None):
    w = qdem.World()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        w.addPiece(mesh, qdem.QdemMat(young=1e6, density=1000.0, viscosity=0.0, radius=radius), ori=ori)
    return [str(x.message) for x in seen if "contact radius" in str(x.message)]


def test_a_radius_thicker_than_the_piece_is_named_with_its_thickness():
    plate = qdem.boxMesh((0.03, 0.02, 0.008), (6, 4, 2))  # a real-size shogi-like piece, 8 mm thick
    msgs = _radiusWarnings(plate, 0.04)
    assert len(msgs) == 1
    assert "0.04 m is 5x the piece's thickness 0.008 m" in msgs[0]
    assert "QdemMat(radius=...)" in msgs[0] and "0.088 m thick" in msgs[0]


@pytest.mark.parametrize("angle,axis", [(0.7, (1, 1, 0)), (2.1, (0.3, -1, 0.4))])
def test_the_thickness_is_found_whatever_the_orientation(angle, axis):
    plate = qdem.boxMesh((0.03, 0.02, 0.008), (6, 4, 2))
    msgs = _radiusWarnings(plate, 0.04, ori=_rotation(angle, axis))
    assert len(msgs) == 1 and "thickness 0.008 m" in msgs[0]


def test_a_radius_of_the_element_size_is_not_named():
    plate = qdem.boxMesh((0.03, 0.02, 0.008), (6, 4, 2))
    assert _radiusWarnings(plate, 0.002) == []
    assert _radiusWarnings(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), 0.04) == []  # r = 0.4 x thickness
