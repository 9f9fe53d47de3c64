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
