"""Springs between two pieces turn with the surfaces' spin (doc/formulation.md,
"Twist"), and that spin decides nothing by rounding: it is continuous over
the surface (interpolated from the nodes' spins), so a contact sliding onto
the next triangle keeps it whichever step the hand-over falls on.  A cube
spinning on a slab, sliding in torsion across the slab's triangles: 1 and 2
threads agree to rounding, two runs at 2 threads bit for bit, 2 MPI ranks
as serially.  (With each triangle's own spin, piecewise constant, 1 and 2
threads parted by 1e-5 m/s.)"""
import sys
from pathlib import Path

import numpy as np

from qdem import _core

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "mpi"))
import check_piece_twist as twist  # noqa: E402  (tests/mpi/check_piece_twist.py: the scene)
from mpi_launch import mpirun, python, requireMpi, result  # noqa: E402


def _run(threads):
    _core.setThreads(threads)
    w = twist.spinningCube()
    x0 = np.array(w.core.pos, copy=True)
    count = twist.run(w)
    return count, x0, np.array(w.core.pos, copy=True), np.array(w.core.vel, copy=True), dict(w.core.energy)


def test_a_spinning_contact_gives_the_same_trajectory_at_one_and_two_threads():
    """1 and 2 threads agree to rounding (measured 2e-15 m, 8e-13 m/s after
    1500 steps, velocities up to 0.05 m/s); two runs at 2 threads bit for
    bit, energy ledger included."""
    n1, x0, x1, v1, _ = _run(1)
    n2, _, x2, v2, e2 = _run(2)
    n2b, _, x2b, v2b, e2b = _run(2)
    assert n1 > 300 and n1 == n2 == n2b  # in contact, the same contacts
    assert np.abs(x1 - x0).max() > 5e-3  # it moved
    assert np.abs(x1 - x2).max() < 1e-13
    assert np.abs(v1 - v2).max() < 1e-10
    assert np.array_equal(x2, x2b) and np.array_equal(v2, v2b)
    assert e2 == e2b


def test_a_spinning_contact_on_two_ranks_as_serially():
    """The slab split under the spinning cube: each rank computes the spins
    of its current nodes from the same data (a contact's triangle and its
    corners' rings lie within the contact halo), so 2 ranks follow the
    serial run to rounding, as 1 and 2 threads do (measured: 1.7e-15 m,
    7.4e-13 m/s; 1 vs 2 threads 1.7e-15 m, 8.5e-13 m/s)."""
    requireMpi()
    rc, out = mpirun(2, python("tests/mpi/check_piece_twist.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["slabRanks"] == [0, 1]  # the slab is split
    assert r["count"] == r["serialCount"] > 300
    d = r["maxDisplacement"]
    assert d > 5e-3
    assert r["dx"] <= max(10 * r["dxThreads"], 1e-13 * d)
    assert r["dv"] <= max(10 * r["dvThreads"], 1e-11 * r["vmax"])


def test_frictionless_pieces_compute_no_spin():
    """The spins are computed only for pieces with a friction partner near
    (frictionless springs have nothing to turn); with friction, for every
    surface node of the pieces in reach of another."""
    import qdem
    counts = []
    for mu in (0.0, 0.5):
        mat = qdem.QdemMat(young=2e6, poisson=0.3, density=1000.0, viscosity=0.0, radius=0.004, restitution=0.5,
                           frictionWall=0.5, frictionPiece=mu)
        w = qdem.World()
        a = w.addPiece(qdem.boxMesh((0.1, 0.1, 0.04), (4, 4, 1)), mat, pos=(0, 0, 0))
        b = w.addPiece(qdem.boxMesh((0.04, 0.04, 0.04), (2, 2, 2)), mat, pos=(0, 0, 0.02 + 0.008 + 0.02 - 0.0005))
        w.core.step(1e-5, 2)
        assert w.core.contactCounts["pointPolygon"] > 0
        counts.append((w.core.contactCounts["surfaceSpinNodes"], len(a.surface()["nodes"]) + len(b.surface()["nodes"])))
    assert counts[0][0] == 0
    assert counts[1][0] == counts[1][1]
