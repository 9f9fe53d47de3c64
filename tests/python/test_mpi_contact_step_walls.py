"""The run-time stable step with a floor's springs in the node loads under
MPI (doc/formulation.md, "Walls and spheres in the same rows"): each node's
floor contact is computed and counted by its owner alone, the piece-piece
shares travel to it with the ghost forces, so every rank reports the serial
limit, node and piece."""
import math

import pytest

from mpi_launch import mpirun, python, requireMpi, result


def test_wall_and_piece_springs_on_a_node_give_the_serial_limit_on_two_ranks():
    requireMpi()
    rc, out = mpirun(2, python("tests/mpi/check_contact_step_walls.py"), timeout=180)
    assert rc == 0, "rc %d (124: timeout)\n%s" % (rc, out[-4000:])
    r = result(out)
    s = r["serial"]["limit"]
    assert math.isfinite(s["pieceContact"]) and s["pieceContactNode"] >= 0
    assert len(r["perRank"]) == 2
    for rank in r["perRank"]:
        d = rank["limit"]
        assert d["pieceContact"] == pytest.approx(s["pieceContact"], rel=1e-12)
        assert d["combined"] == pytest.approx(s["combined"], rel=1e-12)
        for k in ("pieceContactNode", "pieceContactPiece"):
            assert d[k] == s[k], k
