"""OpenMP: 1 and 2 threads give the same trajectory to rounding."""
import numpy as np

import qdem
from conftest import rubber


def _run(threads):
    qdem._core.setThreads(threads)
    w = qdem.World()
    a = w.addPiece(qdem.boxMesh((0.2, 0.2, 0.2), (4, 4, 4)), rubber(viscosity=100.0), vel=(0, 0, -1))
    b = w.addPiece(qdem.boxMesh((0.1, 0.3, 0.1), (2, 6, 2)), rubber(), pos=(0.5, 0, 0), angVel=(3, 0, 0))
    a.pos[:] += 1e-3 * np.sin(13 * a.refPos)
    w.core.gravity = (0, 0, -9.81)
    w.core.step(0.5 * w.stableDt()["combined"], 2000)
    return np.vstack([a.pos, b.pos])


def test_one_and_two_threads_agree():
    try:
        p1, p2 = _run(1), _run(2)
    finally:
        qdem._core.setThreads(2)
    scale = np.abs(p1).max()
    assert np.abs(p1 - p2).max() < 1e-12 * scale


def _collide(threads):
    qdem._core.setThreads(threads)
    w = qdem.World()
    mat = rubber(radius=2e-3, viscosity=50.0, frictionPiece=0.3, restitution=0.5)
    a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), mat, pos=(-0.06, 0.02, 0), vel=(0.5, 0, 0),
                   angVel=(0, 3, 5))
    b = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.1), (4, 4, 4)), mat, pos=(0.06, -0.01, 0.01), ori=((1, 2, 3), 0.5),
                   vel=(-0.5, 0, 0))
    dt = 0.5 * w.stableDt()["combined"]
    hits = 0
    for _ in range(100):
        w.core.step(dt, 20)
        hits += w.core.contactCounts["pointPolygon"] + w.core.contactCounts["edgeEdge"]
    return np.vstack([a.pos, b.pos]), hits


def test_one_and_two_threads_agree_through_contacts():
    try:
        (p1, h1), (p2, h2) = _collide(1), _collide(2)
    finally:
        qdem._core.setThreads(2)
    assert h1 > 0 and h1 == h2
    assert np.abs(p1 - p2).max() < 1e-10 * np.abs(p1).max()
